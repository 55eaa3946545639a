#version 460
#extension GL_GOOGLE_include_directive : require
// Adjoint of field_combine_fwd.comp plus the Eikonal term's gradient: from dL/dsdf, dL/dcos (the
// renderer) and dL/d(colour input) to dL/d(SDF network output) of the four tetrahedron points.
//   g_n = dL/dgradient = dcin[normal] + dL/dcos dir + w_eik 2 (|g| - 1) g / |g|
//   dL/df_k = dL/dsdf / 4 + v_k . g_n / (4h),  dL/dfeature_k = dcin[feature] / 4.
// The view direction is data (no gradient). Host: engine/neus/neus_field.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_neus_field.glsl"

layout(std430, binding = 0) readonly buffer GradColourInput { float gcin[]; };  // [n][cin_stride]
layout(std430, binding = 1) readonly buffer GradSdf { float gsdf[]; };          // [n]
layout(std430, binding = 2) readonly buffer GradCos { float gcos[]; };          // [n]
layout(std430, binding = 3) readonly buffer Gradient { vec4 gradient[]; };      // [n] xyz, |g|
layout(std430, binding = 4) readonly buffer RayDirs { vec4 dirs[]; };           // [n / S]
layout(std430, binding = 5) writeonly buffer GradSdfOutput { float gout[]; };   // [4n][out_stride]

layout(push_constant) uniform Push {
  uint n;
  uint samples_per_ray;
  uint out_stride;
  uint features;
  uint cin_stride;
  float h;
  float eikonal_weight;  // the Eikonal term's weight over the number of samples it averages
  uint has_colour;       // 0: no colour network gradient (mask-only training)
} pc;

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.n) return;
  const vec4 g = gradient[s];
  const vec3 d = dirs[s / pc.samples_per_ray].xyz;
  vec3 gn = gcos[s] * d;
  if (g.w > 1e-12) gn += pc.eikonal_weight * 2.0 * (g.w - 1.0) * g.xyz / g.w;
  const uint row = s * pc.cin_stride;
  if (pc.has_colour != 0u) gn += vec3(gcin[row + pc.features], gcin[row + pc.features + 1u], gcin[row + pc.features + 2u]);
  const float gs = 0.25 * gsdf[s];
  for (uint k = 0u; k < 4u; ++k) {
    const uint o = (4u * s + k) * pc.out_stride;
    gout[o] = gs + dot(nf_tetra_vertex(k), gn) / (4.0 * pc.h);
    for (uint f = 0u; f < pc.features; ++f) gout[o + 1u + f] = pc.has_colour != 0u ? 0.25 * gcin[row + f] : 0.0;
    for (uint c = pc.features + 1u; c < pc.out_stride; ++c) gout[o + c] = 0.0;
  }
}
