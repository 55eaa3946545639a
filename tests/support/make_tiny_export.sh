#!/usr/bin/env bash
# A tiny reconstruction from photos to export, the same small settings as test_cli, for the tests
# that open the export in another program (tests/blender, tests/export).
# Usage: make_tiny_export.sh NF_GPU ANIMAL DIR  (writes DIR/scene and DIR/work; the export is DIR/work/export)
set -euo pipefail
nf_gpu="$1"; animal="$2"; dir="$3"
"$nf_gpu" synth --animal "$animal" --views 8 --res 64 --strands 4000 --spp-axis 1 --out "$dir/scene" >/dev/null
"$nf_gpu" reconstruct --scene "$dir/scene" --out "$dir/work" --quality draft --set knowledge.preset="$animal" \
  --set neus.steps=12 --set neus.rays=128 --set neus.samples_per_ray=16 --set neus.fine_samples=8 --set neus.hull_fit_steps=5 \
  --set neus.mesh_resolution=48 --set neus.hull_resolution=48 --set body.samples=2000 --set body.hypothesis_steps=8 \
  --set body.global_steps=10 --set body.pose_steps=20 --set body.offset_steps=10 --set body.preview_views=1 \
  --set defur.resolution=64 --set defur.preview_views=1 --set frames.roots=3000 --set fur.steps=12 --set fur.warm_steps=4 \
  --set fur.batch=400 --set fur.strands=2500 --set fur.metric_strands=300 --set fur.resolution=64 --set fur.preview_views=1 \
  --set fur.chamfer_queries=500 --set export.turntable_frames=4 --set export.compare_views=1 --set export.formats=usda,hair,ply,obj >/dev/null 2>&1
