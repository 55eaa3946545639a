#version 460
#extension GL_GOOGLE_include_directive : require
// Adjoint of segment_gaussian_fwd: dL/dpoints from dL/dmeans and dL/dcovariances. One invocation per
// point gathers from its (at most two) segments, so no atomics and a deterministic sum.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_segment_gaussian.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };
layout(std430, binding = 1) readonly buffer GradMeans { float grad_means[]; };
layout(std430, binding = 2) readonly buffer GradCovariances { float grad_covs[]; };
layout(std430, binding = 3) buffer GradPoints { float grad_points[]; };

layout(push_constant) uniform Push {
  uint strands;
  uint points_per_strand;
  float k2;
  float eps2;
  float delta2;
  uint accumulate;  // 1: add to grad_points, 0: overwrite
} pc;

vec3 point(uint index) { return vec3(points[index * 3u], points[index * 3u + 1u], points[index * 3u + 2u]); }

// dL/dd and dL/dmean of segment g (whose first point has index `first`).
void segment_grads(uint g, uint first, out vec3 grad_d, out vec3 grad_mean) {
  float gc[6];
  for (uint j = 0u; j < 6u; ++j) gc[j] = grad_covs[g * 6u + j];
  grad_d = nf_segment_covariance_adjoint(point(first + 1u) - point(first), gc, pc.k2, pc.eps2, pc.delta2);
  grad_mean = vec3(grad_means[g * 3u], grad_means[g * 3u + 1u], grad_means[g * 3u + 2u]);
}

void main() {
  const uint L = pc.points_per_strand, segs = L - 1u;
  const uint j = nf_linear_index();
  if (j >= pc.strands * L) return;
  const uint strand = j / L, l = j - strand * L;
  vec3 grad = vec3(0.0), grad_d, grad_mean;
  if (l > 0u) {  // end point of segment l-1
    segment_grads(strand * segs + l - 1u, j - 1u, grad_d, grad_mean);
    grad += 0.5 * grad_mean + grad_d;
  }
  if (l < segs) {  // start point of segment l
    segment_grads(strand * segs + l, j, grad_d, grad_mean);
    grad += 0.5 * grad_mean - grad_d;
  }
  if (pc.accumulate != 0u) grad += vec3(grad_points[j * 3u], grad_points[j * 3u + 1u], grad_points[j * 3u + 2u]);
  grad_points[j * 3u] = grad.x;
  grad_points[j * 3u + 1u] = grad.y;
  grad_points[j * 3u + 2u] = grad.z;
}
