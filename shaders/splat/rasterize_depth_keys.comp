#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, pass 2a: every Gaussian's depth quantised to depth_bits between the near
// and far planes, as a sort key with its index as the value. Sorting the Gaussians by depth once
// and their tile entries by tile afterwards (stable) gives the (tile, depth, index) order with
// far fewer digit passes than sorting every entry by tile and depth: 1.5 M depth keys and 4.4 M
// tile keys at 512x512 for fur. Culled Gaussians sort last (a Gaussian that reaches no tile sorts
// by its depth and writes no entries).

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Proj { float proj[]; };
layout(std430, binding = 1) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = 2) writeonly buffer Order { uint order[]; };

layout(push_constant) uniform Push {
  uint count, depth_bits;
  float near_plane, far_plane;
} pc;

void main() {
  const uint g = nf_linear_index();
  if (g >= pc.count) return;
  const uint top = (pc.depth_bits >= 32u ? 0xffffffffu : (1u << pc.depth_bits) - 1u);
  const float f = clamp((proj[g * 12u + 6u] - pc.near_plane) / (pc.far_plane - pc.near_plane), 0.0, 1.0);
  keys[g] = proj[g * 12u + 11u] == 0.0 ? top : min(uint(f * float(top)), top);
  order[g] = g;
}
