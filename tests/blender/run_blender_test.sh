#!/usr/bin/env bash
# The `blender` ctest entry: a tiny reconstruction from photos to export (the same small settings
# as test_cli), then tests/blender/check_import.py inside Debian's Blender. tools/nf installs
# Blender for this label only (tools/debian-packages-blender.txt).
set -euo pipefail
nf_gpu="$1"; here="$(cd "$(dirname "$0")" && pwd)"; root="$(cd "$here/../.." && pwd)"
command -v blender >/dev/null || { echo "blender is not installed: run tools/nf test -L blender (it installs it)"; exit 1; }
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
"$nf_gpu" synth --animal cat --views 8 --res 64 --strands 4000 --spp-axis 1 --out "$tmp/scene" >/dev/null
"$nf_gpu" reconstruct --scene "$tmp/scene" --out "$tmp/work" --quality draft --set knowledge.preset=cat \
  --set neus.steps=12 --set neus.rays=128 --set neus.samples_per_ray=16 --set neus.fine_samples=8 --set neus.hull_fit_steps=5 \
  --set neus.mesh_resolution=48 --set neus.hull_resolution=48 --set body.samples=2000 --set body.hypothesis_steps=8 \
  --set body.global_steps=10 --set body.pose_steps=20 --set body.offset_steps=10 --set body.preview_views=1 \
  --set defur.resolution=64 --set defur.preview_views=1 --set frames.roots=3000 --set fur.steps=12 --set fur.warm_steps=4 \
  --set fur.batch=400 --set fur.strands=2500 --set fur.metric_strands=300 --set fur.resolution=64 --set fur.preview_views=1 \
  --set fur.chamfer_queries=500 --set export.turntable_frames=2 --set export.compare_views=1 --set export.formats=usda,hair,ply,obj >/dev/null 2>&1
code=0
blender -b --factory-startup --python-exit-code 1 -P "$here/check_import.py" -- "$tmp/work/export" \
  "$root/tools/blender/nf_gpu_import.py" > "$tmp/blender.log" 2>&1 || code=$?
grep -E "^nf_gpu blender test|Error|Traceback|line [0-9]" "$tmp/blender.log" || true
[ "$code" -eq 0 ] && echo "test_blender: passed" || echo "test_blender: FAILED (blender exit $code)"
exit "$code"
