#version 460
#extension GL_GOOGLE_include_directive : require
// Adjoint of frequency_encoding_fwd: dL/dx_d = g_x + sum_l 2^l (g_sin cos(2^l x_d) - g_cos sin(2^l x_d)).
// One sample per invocation, no atomics.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_sincos.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };    // [batch][dims]
layout(std430, binding = 1) readonly buffer GradEncoded { float grad[]; }; // [batch][out4 * 4]
layout(std430, binding = 2) buffer GradPoints { float grad_points[]; };    // [batch][dims]

layout(push_constant) uniform Push {
  uint batch;
  uint dims;
  uint frequencies;
  uint include_input;
  uint out_stride;
  uint accumulate;
} pc;

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.batch) return;
  const uint base = s * pc.out_stride + (pc.include_input != 0u ? pc.dims : 0u);
  for (uint d = 0u; d < pc.dims; ++d) {
    const float x = points[s * pc.dims + d];
    float g = pc.include_input != 0u ? grad[s * pc.out_stride + d] : 0.0;
    for (uint level = 0u; level < pc.frequencies; ++level) {
      const float scale = ldexp(1.0, int(level));
      const float t = nf_reduce_two_pi(x * scale);
      const uint row = base + level * 2u * pc.dims;
      g += scale * (grad[row + d] * cos(t) - grad[row + pc.dims + d] * sin(t));
    }
    const uint i = s * pc.dims + d;
    grad_points[i] = pc.accumulate != 0u ? grad_points[i] + g : g;
  }
}
