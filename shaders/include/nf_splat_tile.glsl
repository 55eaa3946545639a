// The tile side of strand rasterisation; host twin: kTile in engine/splat/rasterizer_ref.hpp.
// 8x8, not the usual 16x16: fur Gaussians are 2-3 px across. With the per-subgroup culling of
// nf_splat_composite.glsl, 16x16 halved the tile sort but doubled compositing on lavapipe (2.4 s
// against 1.6 s forward + backward at 512x512); 4x4 doubles the sort. Composite workgroups have
// NF_TILE^2 / PPI invocations (PPI pixels each: rasterize_fwd.comp).
#ifndef NF_SPLAT_TILE_GLSL
#define NF_SPLAT_TILE_GLSL
const uint NF_TILE = 8u;
#endif
