#!/usr/bin/env bash
# The `chromium` ctest entry: a tiny reconstruction from photos to export
# (tests/support/make_tiny_export.sh), then tests/export/check_page.py opens the export's index.html
# in Debian's headless Chromium. tools/nf installs Chromium for this label only
# (tools/debian-packages-chromium.txt).
set -euo pipefail
nf_gpu="$1"; here="$(cd "$(dirname "$0")" && pwd)"
command -v chromium >/dev/null || { echo "chromium is not installed: run tools/nf test -L chromium (it installs it)"; exit 1; }
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
"$here/../support/make_tiny_export.sh" "$nf_gpu" dog "$tmp"
mkdir -p "$tmp/out"
python3 "$here/check_page.py" "$tmp/work/export" "$tmp/out"
