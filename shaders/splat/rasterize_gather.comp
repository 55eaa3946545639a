#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation: point gradients from the two segments that share each point (no atomics:
// point l of a strand ends segment l-1 and starts segment l).

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer GradSegment { float grad_segment[]; };
layout(std430, binding = 1) buffer GradPoints { float grad_points[]; };

layout(push_constant) uniform Push {
  uint strands, points_per_strand, accumulate;
} pc;

void main() {
  const uint i = nf_linear_index();
  const uint L = pc.points_per_strand, segs = L - 1u;
  if (i >= pc.strands * L) return;
  const uint strand = i / L, l = i - strand * L;
  vec3 g = vec3(0.0);
  if (l < segs) {
    const uint s = (strand * segs + l) * 6u;
    g += vec3(grad_segment[s], grad_segment[s + 1u], grad_segment[s + 2u]);
  }
  if (l > 0u) {
    const uint s = (strand * segs + l - 1u) * 6u + 3u;
    g += vec3(grad_segment[s], grad_segment[s + 1u], grad_segment[s + 2u]);
  }
  for (uint c = 0u; c < 3u; ++c) grad_points[i * 3u + c] = (pc.accumulate != 0u ? grad_points[i * 3u + c] : 0.0) + g[c];
}
