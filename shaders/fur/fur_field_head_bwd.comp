#version 460
#extension GL_GOOGLE_include_directive : require
// Adjoint of the fur field's head (fur_field_head_fwd.comp): the latent rows' gradients back into
// the MLP rows, the segments' confidence gradients summed per strand through softplus' derivative.
// Padding columns get 0. Maths: engine/fur/fur_field_head_ref.hpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Rows { float rows[]; };
layout(std430, binding = 1) readonly buffer GradLatents { float grad_latents[]; };
layout(std430, binding = 2) readonly buffer GradConfidence { float grad_confidence[]; };
layout(std430, binding = 3) writeonly buffer GradRows { float grad_rows[]; };

layout(push_constant) uniform Push {
  uint strands;
  uint latent;
  uint in_stride;
  uint latent_stride;
  uint segments;
} pc;

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.strands) return;
  const uint r0 = s * pc.in_stride, l0 = s * pc.latent_stride;
  float sum = 0.0;
  for (uint j = 0u; j < pc.segments; ++j) sum += grad_confidence[s * pc.segments + j];
  const float q = rows[r0 + pc.latent];
  for (uint j = 0u; j < pc.in_stride; ++j) {
    float g = 0.0;
    if (j < pc.latent) g = grad_latents[l0 + j];
    else if (j == pc.latent) g = sum / (1.0 + exp(-q));
    grad_rows[r0 + j] = g;
  }
}
