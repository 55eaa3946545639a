#version 460
#extension GL_GOOGLE_include_directive : require
// The batch's mean bending angle at each position along the strand: one invocation per position,
// summing over the strands in order (deterministic). Maths: engine/fur/strand_losses_ref.hpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Theta { float theta[]; };  // strands * bends
layout(std430, binding = 1) writeonly buffer Mean { float mean_theta[]; };  // bends

layout(push_constant) uniform Push {
  uint strands;
  uint bends;
} pc;

void main() {
  const uint m = nf_linear_index();
  if (m >= pc.bends) return;
  float sum = 0.0;
  const float inv = 1.0 / float(pc.strands);
  for (uint i = 0u; i < pc.strands; ++i) sum += theta[i * pc.bends + m] * inv;
  mean_theta[m] = sum;
}
