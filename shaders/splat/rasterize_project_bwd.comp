#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, backward of pass 1: per segment, dL/d(12 projected floats) -> dL/dp0,
// dL/dp1 (6 floats per segment, gathered per point by rasterize_gather) and dL/dconfidence.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_splat_camera.glsl"
#include "nf_splat_project.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };
layout(std430, binding = 1) readonly buffer Proj { float proj[]; };
layout(std430, binding = 2) readonly buffer GradProj { float grad_proj[]; };
layout(std430, binding = 3) writeonly buffer GradSegment { float grad_segment[]; };  // per segment: p0 xyz, p1 xyz
layout(std430, binding = 4) writeonly buffer GradConf { float grad_conf[]; };

void main() {
  const uint segs = pc.points_per_strand - 1u;
  const uint g = nf_linear_index();
  if (g >= pc.strands * segs) return;
  vec3 g0 = vec3(0.0), g1 = vec3(0.0);
  float gc = 0.0;
  if (proj[g * 12u + 11u] != 0.0) {
    const uint strand = g / segs, l = g - strand * segs;
    const uint i0 = (strand * pc.points_per_strand + l) * 3u;
    const vec3 p0 = vec3(points[i0], points[i0 + 1u], points[i0 + 2u]);
    const vec3 p1 = vec3(points[i0 + 3u], points[i0 + 4u], points[i0 + 5u]);
    float gp[12];
    for (uint i = 0u; i < 12u; ++i) gp[i] = grad_proj[g * 12u + i];
    nf_project_segment_adjoint(p0, p1, gp, g0, g1);
    gc = gp[P_CONF];
  }
  for (uint c = 0u; c < 3u; ++c) {
    grad_segment[g * 6u + c] = g0[c];
    grad_segment[g * 6u + 3u + c] = g1[c];
  }
  grad_conf[g] = gc;
}
