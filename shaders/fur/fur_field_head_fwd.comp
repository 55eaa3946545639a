#version 460
#extension GL_GOOGLE_include_directive : require
// The fur field's head: MLP rows -> the strand prior's latent rows and each segment's confidence
// softplus(q). One invocation per strand. Maths and layouts: engine/fur/fur_field_head_ref.hpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Rows { float rows[]; };            // strands * in_stride
layout(std430, binding = 1) writeonly buffer Latents { float latents[]; };     // strands * latent_stride
layout(std430, binding = 2) writeonly buffer Confidence { float confidence[]; };  // strands * segments

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
  for (uint j = 0u; j < pc.latent_stride; ++j) latents[l0 + j] = j < pc.latent ? rows[r0 + j] : 0.0;
  const float q = rows[r0 + pc.latent];
  // log1p(e) without the rounding of 1 + e: a strongly negative q keeps its tiny confidence.
  const float e = exp(-abs(q));
  const float c = max(q, 0.0) + (e < 1e-4 ? e - 0.5 * e * e : log(1.0 + e));
  for (uint j = 0u; j < pc.segments; ++j) confidence[s * pc.segments + j] = c;
}
