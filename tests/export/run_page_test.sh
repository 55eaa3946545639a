#!/usr/bin/env bash
# The `chromium` ctest entry: a tiny reconstruction from photos to export (the same small settings
# as test_cli), then tests/export/check_page.py opens the export's index.html in Debian's headless
# Chromium. tools/nf installs Chromium for this label only (tools/debian-packages-chromium.txt).
set -euo pipefail
nf_gpu="$1"; here="$(cd "$(dirname "$0")" && pwd)"
command -v chromium >/dev/null || { echo "chromium is not installed: run tools/nf test -L chromium (it installs it)"; exit 1; }
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
"$nf_gpu" synth --animal dog --views 8 --res 64 --strands 4000 --spp-axis 1 --out "$tmp/scene" >/dev/null
"$nf_gpu" reconstruct --scene "$tmp/scene" --out "$tmp/work" --quality draft --set knowledge.preset=dog \
  --set neus.steps=12 --set neus.rays=128 --set neus.samples_per_ray=16 --set neus.fine_samples=8 --set neus.hull_fit_steps=5 \
  --set neus.mesh_resolution=48 --set neus.hull_resolution=48 --set body.samples=2000 --set body.hypothesis_steps=8 \
  --set body.global_steps=10 --set body.pose_steps=20 --set body.offset_steps=10 --set body.preview_views=1 \
  --set defur.resolution=64 --set defur.preview_views=1 --set frames.roots=3000 --set fur.steps=12 --set fur.warm_steps=4 \
  --set fur.batch=400 --set fur.strands=2500 --set fur.metric_strands=300 --set fur.resolution=64 --set fur.preview_views=1 \
  --set fur.chamfer_queries=500 --set export.turntable_frames=4 --set export.compare_views=1 >/dev/null 2>&1
mkdir -p "$tmp/out"
python3 "$here/check_page.py" "$tmp/work/export" "$tmp/out"
