#version 460
#extension GL_GOOGLE_include_directive : require
// The NeuS image losses per ray, with their gradients:
//   colour: L1 of (colour - target) on rays inside the mask, summed over channels, over the
//           number of such rays (NeuS's colour loss with masks);
//   mask:   binary cross-entropy of the opacity (clamped to [1e-3, 1 - 1e-3], zero gradient
//           where the clamp is active) against the mask, mean over rays.
// Per-workgroup partial sums: colour L1, BCE, squared colour error inside the mask, inside rays.
// Host: engine/neus/render_loss.cpp.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Colour { float colour[]; };        // [R][3]
layout(std430, binding = 1) readonly buffer Opacity { float opacity[]; };      // [R]
layout(std430, binding = 2) readonly buffer Target { vec4 target[]; };         // [R] rgb, mask
layout(std430, binding = 3) writeonly buffer GradColour { float gcolour[]; };  // [R][3]
layout(std430, binding = 4) writeonly buffer GradOpacity { float gopacity[]; };// [R]
layout(std430, binding = 5) writeonly buffer Partials { vec4 partials[]; };    // [groups]

layout(push_constant) uniform Push {
  uint rays;
  float colour_weight;  // colour weight / number of rays inside the mask
  float mask_weight;    // mask weight / number of rays
} pc;

shared vec4 sums[WG];

void main() {
  if (nf_linear_group() * WG >= pc.rays) return;
  const uint r = nf_linear_index();
  vec4 part = vec4(0.0);
  if (r < pc.rays) {
    const vec4 t = target[r];
    const bool inside = t.w > 0.5;
    for (uint c = 0u; c < 3u; ++c) {
      const float e = colour[3u * r + c] - t[c];
      gcolour[3u * r + c] = inside ? pc.colour_weight * sign(e) : 0.0;
      if (inside) {
        part.x += abs(e);
        part.z += e * e;
      }
    }
    part.w = inside ? 1.0 : 0.0;
    const float o = opacity[r];
    const float oc = clamp(o, 1e-3, 1.0 - 1e-3);
    part.y = -(t.w * log(oc) + (1.0 - t.w) * log(1.0 - oc));
    gopacity[r] = o == oc ? pc.mask_weight * (oc - t.w) / (oc * (1.0 - oc)) : 0.0;
  }
  const vec4 total = subgroupAdd(part);
  if (subgroupElect()) sums[gl_SubgroupID] = total;
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    vec4 sum = vec4(0.0);
    for (uint k = 0u; k < gl_NumSubgroups; ++k) sum += sums[k];
    partials[nf_linear_group()] = sum;
  }
}
