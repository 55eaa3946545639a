#version 460
#extension GL_GOOGLE_include_directive : require
// Exclusive scan, pass 1 of 2: the sum of each block of WG*ITEMS elements.
// The `flags` variant counts non-zero elements instead (stream compaction).
//! variant add
//! variant flags -DNF_SCAN_FLAGS
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(constant_id = 0) const uint WG = 256;
layout(constant_id = 1) const uint ITEMS = 4;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_workgroup.glsl"

layout(std430, binding = 0) readonly buffer Input { uint data[]; };
layout(std430, binding = 1) writeonly buffer BlockSums { uint block_sums[]; };

layout(push_constant) uniform Push { uint n; } pc;

uint load(uint i) {
  if (i >= pc.n) return 0u;
#ifdef NF_SCAN_FLAGS
  return data[i] != 0u ? 1u : 0u;
#else
  return data[i];
#endif
}

void main() {
  const uint block = nf_linear_group();
  const uint base = block * WG * ITEMS;
  if (base >= pc.n) return;
  uint sum = 0u;
  for (uint k = 0; k < ITEMS; ++k) sum += load(base + k * WG + gl_LocalInvocationID.x);
  const uint total = nf_wg_add(uvec4(sum, 0, 0, 0)).x;
  if (gl_LocalInvocationIndex == 0) block_sums[block] = total;
}
