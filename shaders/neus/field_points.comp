#version 460
#extension GL_GOOGLE_include_directive : require
// The four evaluation points of each sample for tetrahedral finite differences (NeuS2-style
// numerical normals): p_k = x + h v_k, v = (1,-1,-1), (-1,-1,1), (-1,1,-1), (1,1,1). Writes the
// encoder's input (scaled and shifted: [0,1]^3 for the hash grid) and, when asked, the raw
// position into the first three columns of the SDF network's rows. Host: engine/neus/neus_field.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_neus_field.glsl"

layout(std430, binding = 0) readonly buffer Samples { vec4 samples[]; };       // [n] xyz (unit sphere)
layout(std430, binding = 1) writeonly buffer EncoderPoints { float points[]; }; // [4n][3]
layout(std430, binding = 2) writeonly buffer SdfInput { float sdf_in[]; };      // [4n][in_stride]

layout(push_constant) uniform Push {
  uint n;
  uint in_stride;
  uint write_position;
  float h;
  float point_scale;
  float point_offset;
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i >= 4u * pc.n) return;
  const vec3 p = samples[i >> 2].xyz + pc.h * nf_tetra_vertex(i & 3u);
  const vec3 e = p * pc.point_scale + pc.point_offset;
  points[3u * i] = e.x;
  points[3u * i + 1u] = e.y;
  points[3u * i + 2u] = e.z;
  if (pc.write_position != 0u) {
    sdf_in[i * pc.in_stride] = p.x;
    sdf_in[i * pc.in_stride + 1u] = p.y;
    sdf_in[i * pc.in_stride + 2u] = p.z;
  }
}
