#version 460
#extension GL_GOOGLE_include_directive : require
// NeuS volume rendering forward: one invocation per ray composites its S samples front to back into
// colour (3 floats) and opacity. Host wrapper: engine/neus/volume_render.cpp; maths:
// engine/neus/volume_render_ref.hpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_neus_volume_render.glsl"

layout(std430, binding = 0) readonly buffer Sdf { float sdf[]; };    // [rays][S]
layout(std430, binding = 1) readonly buffer Cos { float cs[]; };     // [rays][S]
layout(std430, binding = 2) readonly buffer Dist { float dist[]; };  // [rays][S]
layout(std430, binding = 3) readonly buffer Rgb { float rgb[]; };    // [rays][S][3]
layout(std430, binding = 4) writeonly buffer Colour { float colour[]; };    // [rays][3]
layout(std430, binding = 5) writeonly buffer Opacity { float opacity[]; };  // [rays]

layout(push_constant) uniform Push {
  uint rays;  // in this chunk
  uint samples;
  float inv_s;
  float anneal;
} pc;

void main() {
  const uint r = nf_linear_index();
  if (r >= pc.rays) return;
  float trans = 1.0, op = 0.0;
  vec3 col = vec3(0.0);
  vec3 unused;
  for (uint i = 0u; i < pc.samples; ++i) {
    const uint k = r * pc.samples + i;
    const float alpha = nf_vr_sample(sdf[k], cs[k], dist[k], pc.inv_s, pc.anneal, false, unused);
    const float w = alpha * trans;
    col += w * vec3(rgb[3u * k], rgb[3u * k + 1u], rgb[3u * k + 2u]);
    op += w;
    trans *= 1.0 - alpha + 1e-7;
  }
  colour[3u * r] = col.x;
  colour[3u * r + 1u] = col.y;
  colour[3u * r + 2u] = col.z;
  opacity[r] = op;
}
