#version 460
#extension GL_GOOGLE_include_directive : require
// Adjoint of volume_render_fwd: one invocation per ray. A forward sweep recomputes T_i and stashes
// it in this ray's own grad_sdf slots; the backward walk (i = S-1..0) keeps the suffix R (remaining
// radiance at unit transmittance), uses dL/dalpha_i = T_i (g_i - R_{i+1}) and overwrites the slots
// with dL/dsdf. Division-free and exact. dL/dinv_s: subgroup sum, then one float atomic per
// subgroup into grad_inv_s (zeroed by the host). Maths: engine/neus/volume_render_ref.hpp.
#extension GL_EXT_shader_atomic_float : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_neus_volume_render.glsl"

layout(std430, binding = 0) readonly buffer Sdf { float sdf[]; };    // [rays][S]
layout(std430, binding = 1) readonly buffer Cos { float cs[]; };     // [rays][S]
layout(std430, binding = 2) readonly buffer Dist { float dist[]; };  // [rays][S]
layout(std430, binding = 3) readonly buffer Rgb { float rgb[]; };    // [rays][S][3]
layout(std430, binding = 4) readonly buffer GradColour { float grad_colour[]; };    // [rays][3]
layout(std430, binding = 5) readonly buffer GradOpacity { float grad_opacity[]; };  // [rays]
layout(std430, binding = 6) buffer GradSdf { float grad_sdf[]; };              // [rays][S]
layout(std430, binding = 7) writeonly buffer GradCos { float grad_cos[]; };    // [rays][S]
layout(std430, binding = 8) writeonly buffer GradRgb { float grad_rgb[]; };    // [rays][S][3]
layout(std430, binding = 9) buffer GradInvS { float grad_inv_s[]; };           // [1], accumulated

layout(push_constant) uniform Push {
  uint rays;  // in this chunk
  uint samples;
  float inv_s;
  float anneal;
} pc;

void main() {
  const uint r = nf_linear_index();
  float ds = 0.0;
  if (r < pc.rays) {
    const uint base = r * pc.samples;
    vec3 d;
    float trans = 1.0;
    for (uint i = 0u; i < pc.samples; ++i) {
      const uint k = base + i;
      grad_sdf[k] = trans;
      trans *= 1.0 - nf_vr_sample(sdf[k], cs[k], dist[k], pc.inv_s, pc.anneal, false, d) + 1e-7;
    }
    const vec3 gc = vec3(grad_colour[3u * r], grad_colour[3u * r + 1u], grad_colour[3u * r + 2u]);
    const float go = grad_opacity[r];
    float rest = 0.0;
    for (uint i = pc.samples; i-- > 0u;) {
      const uint k = base + i;
      const float alpha = nf_vr_sample(sdf[k], cs[k], dist[k], pc.inv_s, pc.anneal, true, d);
      const vec3 c = vec3(rgb[3u * k], rgb[3u * k + 1u], rgb[3u * k + 2u]);
      const float gi = dot(gc, c) + go;
      const float t = grad_sdf[k];
      const vec3 gw = (alpha * t) * gc;
      grad_rgb[3u * k] = gw.x;
      grad_rgb[3u * k + 1u] = gw.y;
      grad_rgb[3u * k + 2u] = gw.z;
      const float ga = t * (gi - rest);
      grad_sdf[k] = ga * d.x;
      grad_cos[k] = ga * d.y;
      ds += ga * d.z;
      rest = alpha * gi + (1.0 - alpha + 1e-7) * rest;
    }
  }
  const float sum = subgroupAdd(ds);
  if (subgroupElect() && sum != 0.0) atomicAdd(grad_inv_s[0], sum);
}
