#version 460
#extension GL_GOOGLE_include_directive : require
// Strand points from the decoder's segment vectors: running sum, arc length normalised to the
// root's fur length, turned from the root's frame into the world. One invocation per strand.
// The maths and layouts: engine/fur/strand_geometry_ref.hpp. Host wrapper: engine/fur/strand_geometry.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Rows { float rows[]; };        // strands * row_stride
layout(std430, binding = 1) readonly buffer Frames { float frames[]; };    // strands * 13
layout(std430, binding = 2) writeonly buffer Points { float points[]; };   // strands * (S + 1) * 3

layout(push_constant) uniform Push {
  uint strands;
  uint segments;
  uint row_stride;
  float delta2;  // arc-length guard squared
} pc;

vec3 segment(uint r0, uint j) { return vec3(rows[r0 + 3u * j], rows[r0 + 3u * j + 1u], rows[r0 + 3u * j + 2u]); }
vec3 frame_vec(uint f0, uint at) { return vec3(frames[f0 + at], frames[f0 + at + 1u], frames[f0 + at + 2u]); }

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.strands) return;
  const uint r0 = s * pc.row_stride, f0 = s * 13u, p0 = s * (pc.segments + 1u) * 3u;
  float arc = 0.0;
  for (uint j = 0u; j < pc.segments; ++j) {
    const vec3 d = segment(r0, j);
    arc += sqrt(dot(d, d) + pc.delta2);
  }
  const vec3 root = frame_vec(f0, 0u), T = frame_vec(f0, 4u), B = frame_vec(f0, 7u), N = frame_vec(f0, 10u);
  const float scale = frames[f0 + 3u] / arc;
  vec3 local = vec3(0.0);
  for (uint k = 0u; k <= pc.segments; ++k) {
    if (k > 0u) local += segment(r0, k - 1u);
    const vec3 p = root + scale * (T * local.x + B * local.y + N * local.z);
    points[p0 + 3u * k] = p.x;
    points[p0 + 3u * k + 1u] = p.y;
    points[p0 + 3u * k + 2u] = p.z;
  }
}
