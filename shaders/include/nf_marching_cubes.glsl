// Marching cubes on the GPU, shared by shaders/geometry/marching_cubes_{count,emit}.comp: the case
// table as engine/geometry/marching_cubes_gpu.cpp packs it from the generated table of
// engine/geometry/marching_cubes_table.hpp, and the inside rule.
// Include after defining `float mc_value(uvec3 p)` (the sample at grid point p).
#ifndef NF_MARCHING_CUBES_GLSL
#define NF_MARCHING_CUBES_GLSL

// NF_MC_ROW uints per case: [0] its triangle count, then one edge code per triangle corner, wound
// so that the right-hand normal points from inside (value < iso) to outside. An edge code names a
// cube edge by the grid edge that carries it: bits 0-1 the axis, bits 2-4 the x, y, z offsets of
// its low corner from the cube's lowest corner.
const uint NF_MC_ROW = 16u;

uint nf_mc_axis(uint code) { return code & 3u; }
uvec3 nf_mc_corner(uint code) { return uvec3((code >> 2) & 1u, (code >> 3) & 1u, (code >> 4) & 1u); }

// Neither NaN nor Inf, read from the exponent bits so that no float optimisation can fold it away.
bool nf_mc_finite(float v) { return (floatBitsToUint(v) & 0x7f800000u) != 0x7f800000u; }

// The case of the cell whose lowest corner is p: bit c set when corner c = x + 2y + 4z is inside.
uint nf_mc_case(uvec3 p, float iso) {
  uint c = 0u;
  for (uint k = 0u; k < 8u; ++k)
    if (mc_value(p + uvec3(k & 1u, (k >> 1) & 1u, (k >> 2) & 1u)) < iso) c |= 1u << k;
  return c;
}

#endif
