#version 460
#extension GL_GOOGLE_include_directive : require
// Per sample: the SDF (mean of the four tetrahedron values), its gradient (finite differences),
// the geometry features (mean of the four), cos = dir . gradient for the renderer, the colour
// network's input row [features, gradient, view direction], and per-workgroup partial sums of the
// Eikonal term (|gradient| - 1)^2. Adjoint: field_combine_bwd.comp. Host: engine/neus/neus_field.cpp.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_neus_field.glsl"

layout(std430, binding = 0) readonly buffer SdfOutput { float sdf_out[]; };   // [4n][out_stride]
layout(std430, binding = 1) readonly buffer RayDirs { vec4 dirs[]; };         // [n / S]
layout(std430, binding = 2) writeonly buffer ColourInput { float cin[]; };    // [n][cin_stride]
layout(std430, binding = 3) writeonly buffer Sdf { float sdf[]; };            // [n]
layout(std430, binding = 4) writeonly buffer Cos { float cosines[]; };        // [n]
layout(std430, binding = 5) writeonly buffer Gradient { vec4 gradient[]; };   // [n] xyz, |g|
layout(std430, binding = 6) writeonly buffer Partials { float partials[]; };  // [groups]

layout(push_constant) uniform Push {
  uint n;
  uint samples_per_ray;
  uint out_stride;
  uint features;
  uint cin_stride;
  float h;
} pc;

shared float sums[WG];

void main() {
  if (nf_linear_group() * WG >= pc.n) return;
  const uint s = nf_linear_index();
  float eikonal = 0.0;
  if (s < pc.n) {
    float mean = 0.0;
    vec3 g = vec3(0.0);
    for (uint k = 0u; k < 4u; ++k) {
      const float f = sdf_out[(4u * s + k) * pc.out_stride];
      mean += f;
      g += f * nf_tetra_vertex(k);
    }
    g /= 4.0 * pc.h;
    const vec3 d = dirs[s / pc.samples_per_ray].xyz;
    const float len = length(g);
    sdf[s] = 0.25 * mean;
    cosines[s] = dot(d, g);
    gradient[s] = vec4(g, len);
    eikonal = (len - 1.0) * (len - 1.0);
    const uint row = s * pc.cin_stride;
    for (uint f = 0u; f < pc.features; ++f) {
      float sum = 0.0;
      for (uint k = 0u; k < 4u; ++k) sum += sdf_out[(4u * s + k) * pc.out_stride + 1u + f];
      cin[row + f] = 0.25 * sum;
    }
    for (uint a = 0u; a < 3u; ++a) {
      cin[row + pc.features + a] = g[a];
      cin[row + pc.features + 3u + a] = d[a];
    }
    for (uint c = pc.features + 6u; c < pc.cin_stride; ++c) cin[row + c] = 0.0;
  }
  const float total = subgroupAdd(eikonal);
  if (subgroupElect()) sums[gl_SubgroupID] = total;
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    float sum = 0.0;
    for (uint k = 0u; k < gl_NumSubgroups; ++k) sum += sums[k];
    partials[nf_linear_group()] = sum;
  }
}
