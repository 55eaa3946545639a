#version 460
#extension GL_GOOGLE_include_directive : require
// The fur stage's geometric strand losses, per strand before normalisation: growth direction
// against the knowledge (weighted root to tip), squared deviation of the bending angles from the
// batch's mean, and depth inside the bald body (trilinear SDF). One invocation per strand; the host
// sums and normalises. Maths: engine/fur/strand_losses_ref.hpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_strand_losses.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };
layout(std430, binding = 1) readonly buffer Guides { float guides[]; };    // strands * 3
layout(std430, binding = 2) readonly buffer Lengths { float lengths[]; };
layout(std430, binding = 3) readonly buffer Theta { float theta[]; };      // strands * (L - 2)
layout(std430, binding = 4) readonly buffer Mean { float mean_theta[]; };  // L - 2
layout(std430, binding = 5) readonly buffer Sdf { float sdf[]; };          // nz * ny * nx
layout(std430, binding = 6) writeonly buffer Partial { float partial[]; }; // strands * 3

layout(push_constant) uniform Push {
  uint strands;
  uint points_per_strand;
  float guard_fraction;
  int nx, ny, nz;
  float ox, oy, oz;
  float spacing;
} pc;

#include "nf_strand_sdf.glsl"

vec3 point(uint i) { return vec3(points[3u * i], points[3u * i + 1u], points[3u * i + 2u]); }

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.strands) return;
  const uint L = pc.points_per_strand, first = s * L, S = L - 1u, B = L - 2u;
  const float delta = pc.guard_fraction * lengths[s] / float(S), delta2 = delta * delta;
  const vec3 g = vec3(guides[3u * s], guides[3u * s + 1u], guides[3u * s + 2u]);
  float direction = 0.0, curvature = 0.0, penetration = 0.0;
  for (uint l = 0u; l < S; ++l) {
    const vec3 b = nf_unit(point(first + l + 1u) - point(first + l), delta2);
    direction += float(l) / float(S) * max(0.0, -dot(b, g));
  }
  for (uint m = 0u; m < B; ++m) {
    const float e = theta[s * B + m] - mean_theta[m];
    curvature += e * e;
  }
  vec3 unused;
  for (uint k = 0u; k < L; ++k) penetration += max(0.0, -nf_sdf_sample(point(first + k), false, unused));
  partial[3u * s] = direction;
  partial[3u * s + 1u] = curvature;
  partial[3u * s + 2u] = penetration;
}
