#version 460
#extension GL_GOOGLE_include_directive : require
// Radix sort pass, step 1: per-block digit histogram, stored bin-major (hist[bin * blocks + block])
// so that one exclusive scan of the whole array yields every block's output offset per bin.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "nf_radix.glsl"

layout(constant_id = 0) const uint WG = 128;
layout(constant_id = 1) const uint ITEMS = 8;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_workgroup.glsl"

layout(std430, binding = 0) readonly buffer Keys { uint keys[]; };
layout(std430, binding = 1) writeonly buffer Histogram { uint hist[]; };

layout(push_constant) uniform Push {
  uint n;
  uint shift;
  uint blocks;
} pc;

void main() {
  const uint block = nf_linear_group();
  if (block >= pc.blocks) return;
  const uint base = block * WG * ITEMS;
  uvec4 lo = uvec4(0), hi = uvec4(0);
  for (uint k = 0; k < ITEMS; ++k) {
    const uint i = base + k * WG + gl_LocalInvocationID.x;
    if (i < pc.n) nf_radix_count(nf_radix_digit(keys[i], pc.shift), lo, hi);
  }
  lo = nf_wg_add(lo);
  hi = nf_wg_add(hi);
  const uint bin = gl_LocalInvocationIndex;
  if (bin < NF_RADIX_BINS) hist[bin * pc.blocks + block] = nf_radix_field(bin, lo, hi);
}
