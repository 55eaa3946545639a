#version 460
#extension GL_GOOGLE_include_directive : require
// Bending angles of every strand (L - 2 each) for the curvature-consistency loss; their batch mean
// is taken by strand_bending_mean.comp. One invocation per strand. Maths: engine/fur/strand_losses_ref.hpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_strand_losses.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };    // strands * L * 3
layout(std430, binding = 1) readonly buffer Lengths { float lengths[]; };  // strands
layout(std430, binding = 2) writeonly buffer Theta { float theta[]; };     // strands * (L - 2)

layout(push_constant) uniform Push {
  uint strands;
  uint points_per_strand;
  float guard_fraction;  // delta = guard_fraction * length / (L - 1)
} pc;

vec3 point(uint i) { return vec3(points[3u * i], points[3u * i + 1u], points[3u * i + 2u]); }

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.strands) return;
  const uint L = pc.points_per_strand, first = s * L;
  const float delta = pc.guard_fraction * lengths[s] / float(L - 1u), delta2 = delta * delta;
  vec3 prev = nf_unit(point(first + 1u) - point(first), delta2);
  for (uint l = 1u; l + 1u < L; ++l) {
    const vec3 b = nf_unit(point(first + l + 1u) - point(first + l), delta2);
    theta[s * (L - 2u) + l - 1u] = nf_bend(prev, b);
    prev = b;
  }
}
