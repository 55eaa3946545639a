#!/usr/bin/env bash
# The `blender` ctest entry: a tiny reconstruction from photos to export
# (tests/support/make_tiny_export.sh), then tests/blender/check_import.py inside Debian's Blender.
# tools/nf installs Blender for this label only (tools/debian-packages-blender.txt).
set -euo pipefail
nf_gpu="$1"; here="$(cd "$(dirname "$0")" && pwd)"; root="$(cd "$here/../.." && pwd)"
command -v blender >/dev/null || { echo "blender is not installed: run tools/nf test -L blender (it installs it)"; exit 1; }
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
"$root/tests/support/make_tiny_export.sh" "$nf_gpu" cat "$tmp"
code=0
blender -b --factory-startup --python-exit-code 1 -P "$here/check_import.py" -- "$tmp/work/export" \
  "$root/tools/blender/nf_gpu_import.py" > "$tmp/blender.log" 2>&1 || code=$?
grep -E "^nf_gpu blender test|Error|Traceback|line [0-9]" "$tmp/blender.log" || true
[ "$code" -eq 0 ] && echo "test_blender: passed" || echo "test_blender: FAILED (blender exit $code)"
exit "$code"
