#version 460
#extension GL_GOOGLE_include_directive : require
// Adjoint of strand_geometry_fwd: dLoss/d(segment vectors) and dLoss/d(root, length, frame) from
// dLoss/dpoints. One invocation per strand, three passes over its points: the arc length; the
// projected gradients' dot with the running sum (for the arc length's share) and the frame's
// gradients; then the suffix sums from the tip down. The maths: engine/fur/strand_geometry_ref.hpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Rows { float rows[]; };
layout(std430, binding = 1) readonly buffer Frames { float frames[]; };
layout(std430, binding = 2) readonly buffer GradPoints { float grad_points[]; };
layout(std430, binding = 3) writeonly buffer GradRows { float grad_rows[]; };
layout(std430, binding = 4) writeonly buffer GradFrames { float grad_frames[]; };

layout(push_constant) uniform Push {
  uint strands;
  uint segments;
  uint row_stride;
  float delta2;
} pc;

vec3 segment(uint r0, uint j) { return vec3(rows[r0 + 3u * j], rows[r0 + 3u * j + 1u], rows[r0 + 3u * j + 2u]); }
vec3 frame_vec(uint f0, uint at) { return vec3(frames[f0 + at], frames[f0 + at + 1u], frames[f0 + at + 2u]); }
vec3 grad_point(uint p0, uint k) { return vec3(grad_points[p0 + 3u * k], grad_points[p0 + 3u * k + 1u], grad_points[p0 + 3u * k + 2u]); }

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.strands) return;
  const uint r0 = s * pc.row_stride, f0 = s * 13u, p0 = s * (pc.segments + 1u) * 3u;
  float arc = 0.0;
  for (uint j = 0u; j < pc.segments; ++j) {
    const vec3 d = segment(r0, j);
    arc += sqrt(dot(d, d) + pc.delta2);
  }
  const vec3 T = frame_vec(f0, 4u), B = frame_vec(f0, 7u), N = frame_vec(f0, 10u);
  const mat3 M = mat3(T, B, N);  // columns: local -> world
  const float scale = frames[f0 + 3u] / arc;
  vec3 local = vec3(0.0), g_root = vec3(0.0), g_T = vec3(0.0), g_B = vec3(0.0), g_N = vec3(0.0);
  float dot_sum = 0.0;
  for (uint k = 0u; k <= pc.segments; ++k) {
    if (k > 0u) local += segment(r0, k - 1u);
    const vec3 G = grad_point(p0, k);
    dot_sum += dot(transpose(M) * G, local);
    g_root += G;
    g_T += (scale * local.x) * G;
    g_B += (scale * local.y) * G;
    g_N += (scale * local.z) * G;
  }
  const float grad_arc = -scale * dot_sum / arc;
  vec3 suffix = vec3(0.0);
  for (uint j = pc.segments; j-- > 0u;) {
    suffix += scale * (transpose(M) * grad_point(p0, j + 1u));
    const vec3 d = segment(r0, j);
    const vec3 g = suffix + grad_arc * d / sqrt(dot(d, d) + pc.delta2);
    grad_rows[r0 + 3u * j] = g.x;
    grad_rows[r0 + 3u * j + 1u] = g.y;
    grad_rows[r0 + 3u * j + 2u] = g.z;
  }
  for (uint c = 3u * pc.segments; c < pc.row_stride; ++c) grad_rows[r0 + c] = 0.0;  // the row's padding
  const float g_frame[13] = float[13](g_root.x, g_root.y, g_root.z, dot_sum / arc, g_T.x, g_T.y, g_T.z, g_B.x, g_B.y, g_B.z,
                                      g_N.x, g_N.y, g_N.z);
  for (uint c = 0u; c < 13u; ++c) grad_frames[f0 + c] = g_frame[c];
}
