#version 460
#extension GL_GOOGLE_include_directive : require
// Optimiser step, pass 1: per workgroup, the sum of squares of the finite gradients and the count
// of non-finite ones. adam_prepare reduces these partials.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Grads { float grads[]; };
layout(std430, binding = 1) writeonly buffer Partials { vec2 partials[]; };  // (sum of squares, non-finite)

layout(push_constant) uniform Push {
  uint count;
  uint per_group;
} pc;

shared vec2 sums[WG];

void main() {
  const uint group = nf_linear_group();
  const uint begin = group * pc.per_group, end = min(pc.count, begin + pc.per_group);
  float squares = 0.0, bad = 0.0;
  for (uint i = begin + gl_LocalInvocationID.x; i < end; i += WG) {
    const float g = grads[i];
    // Exponent all ones: NaN or Inf. A bit test, because without SignedZeroInfNanPreserve a compiler
    // may assume isnan/isinf are false.
    if ((floatBitsToUint(g) & 0x7f800000u) == 0x7f800000u) bad += 1.0;
    else squares += g * g;
  }
  const vec2 total = subgroupAdd(vec2(squares, bad));
  if (subgroupElect()) sums[gl_SubgroupID] = total;
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    vec2 s = vec2(0.0);
    for (uint i = 0u; i < gl_NumSubgroups; ++i) s += sums[i];
    partials[group] = s;
  }
}
