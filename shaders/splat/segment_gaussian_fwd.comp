#version 460
#extension GL_GOOGLE_include_directive : require
// One Gaussian per strand segment: mean at the midpoint, covariance eps^2 I + (k^2 - eps^2/|d|^2) d d^T.
// One invocation per segment. Host wrapper: engine/splat/segment_gaussian.cpp.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_segment_gaussian.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };      // strands * L * 3
layout(std430, binding = 1) writeonly buffer Means { float means[]; };       // strands * (L-1) * 3
layout(std430, binding = 2) writeonly buffer Covariances { float covs[]; };  // strands * (L-1) * 6

layout(push_constant) uniform Push {
  uint strands;
  uint points_per_strand;
  float k2;      // length_scale^2
  float eps2;    // width^2
  float delta2;  // guard^2
} pc;

void main() {
  const uint segs = pc.points_per_strand - 1u;
  const uint g = nf_linear_index();
  if (g >= pc.strands * segs) return;
  const uint strand = g / segs, l = g - strand * segs;
  const uint i0 = (strand * pc.points_per_strand + l) * 3u;
  const vec3 p0 = vec3(points[i0], points[i0 + 1u], points[i0 + 2u]);
  const vec3 p1 = vec3(points[i0 + 3u], points[i0 + 4u], points[i0 + 5u]);
  const vec3 mean = 0.5 * (p0 + p1);
  means[g * 3u] = mean.x;
  means[g * 3u + 1u] = mean.y;
  means[g * 3u + 2u] = mean.z;
  float cov[6];
  nf_segment_covariance(p1 - p0, pc.k2, pc.eps2, pc.delta2, cov);
  for (uint j = 0u; j < 6u; ++j) covs[g * 6u + j] = cov[j];
}
