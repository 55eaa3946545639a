#version 460
#extension GL_GOOGLE_include_directive : require
// Adjoint of the one-way chamfer: each strand point sums 2 w / K (p_j - x_k) over the queries whose
// nearest point it is (the queries sorted by nearest point, with each point's range). A gather, so
// no float atomics and a deterministic sum. Host wrapper: engine/fur/strand_chamfer.cpp.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Queries { float queries[]; };
layout(std430, binding = 1) readonly buffer Points { float points[]; };
layout(std430, binding = 2) readonly buffer SortedQueries { uint sorted_queries[]; };
layout(std430, binding = 3) readonly buffer Start { uint start[]; };
layout(std430, binding = 4) readonly buffer End { uint end_[]; };
layout(std430, binding = 5) buffer GradPoints { float grad_points[]; };

layout(push_constant) uniform Push {
  uint count;       // strand points
  float scale;      // 2 w / K
  uint accumulate;  // 1: add to grad_points
} pc;

void main() {
  const uint j = nf_linear_index();
  if (j >= pc.count) return;
  const vec3 p = vec3(points[3u * j], points[3u * j + 1u], points[3u * j + 2u]);
  vec3 g = vec3(0.0);
  for (uint i = start[j]; i < end_[j]; ++i) {
    const uint k = sorted_queries[i];
    g += p - vec3(queries[3u * k], queries[3u * k + 1u], queries[3u * k + 2u]);
  }
  g *= pc.scale;
  if (pc.accumulate != 0u) g += vec3(grad_points[3u * j], grad_points[3u * j + 1u], grad_points[3u * j + 2u]);
  grad_points[3u * j] = g.x;
  grad_points[3u * j + 1u] = g.y;
  grad_points[3u * j + 2u] = g.z;
}
