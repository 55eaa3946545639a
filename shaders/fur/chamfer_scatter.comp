#version 460
#extension GL_GOOGLE_include_directive : require
// Adjoint of the one-way chamfer: with the queries sorted by their nearest strand point, the first
// query of each run sums 2 w / K (p_j - x_k) over the run and writes point j's gradient. One
// invocation per query, not per strand point (queries are 100x fewer), no float atomics, and the
// same sum in the same order every time. It adds to grad_points (the host zero-fills it when the
// gradient is not accumulated). Host wrapper: engine/fur/strand_chamfer.cpp.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Queries { float queries[]; };
layout(std430, binding = 1) readonly buffer Points { float points[]; };
layout(std430, binding = 2) readonly buffer Keys { uint nearest_sorted[]; };   // nearest point, ascending
layout(std430, binding = 3) readonly buffer Ids { uint sorted_queries[]; };    // query of each key
layout(std430, binding = 4) buffer GradPoints { float grad_points[]; };

layout(push_constant) uniform Push {
  uint count;       // queries
  float scale;  // 2 w / K
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.count) return;
  const uint j = nearest_sorted[i];
  if (j == 0xffffffffu || (i > 0u && nearest_sorted[i - 1u] == j)) return;  // unmatched, or not a run's head
  // A run is at most the host's cap on queries (kMaxChamferQueries) long: lavapipe ends loops past
  // 65,535 iterations.
  const vec3 p = vec3(points[3u * j], points[3u * j + 1u], points[3u * j + 2u]);
  vec3 g = vec3(0.0);
  for (uint at = i; at < pc.count && nearest_sorted[at] == j; ++at) {
    const uint k = sorted_queries[at];
    g += p - vec3(queries[3u * k], queries[3u * k + 1u], queries[3u * k + 2u]);
  }
  g *= pc.scale;
  grad_points[3u * j] = g.x + grad_points[3u * j];
  grad_points[3u * j + 1u] = g.y + grad_points[3u * j + 1u];
  grad_points[3u * j + 2u] = g.z + grad_points[3u * j + 2u];
}
