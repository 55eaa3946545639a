// The tile side of strand rasterisation; host twin: kTile in engine/splat/rasterizer_ref.hpp.
// 8x8, not the usual 16x16: fur Gaussians are 2-3 px across, so a 16x16 tile evaluates ten pixels
// for every one a Gaussian covers; 8x8 halved forward and backward time on lavapipe (4x4 gained
// little more and doubles the sort). Composite workgroups have NF_TILE^2 invocations.
#ifndef NF_SPLAT_TILE_GLSL
#define NF_SPLAT_TILE_GLSL
const uint NF_TILE = 8u;
#endif
