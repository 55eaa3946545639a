#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, pass 2: every Gaussian writes one (tile, quantised depth) key per tile it
// reaches (the tiles rasterize_project counted, by the same test), at the offset the scan of tile
// counts gave it; the value is the Gaussian's index. Should the two passes ever disagree, the
// count wins: no slot past it is written and unused slots get a key past every tile.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_splat_tile.glsl"
#include "nf_splat_reach.glsl"

layout(std430, binding = 0) readonly buffer Proj { float proj[]; };
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 2) readonly buffer Rects { uint rects[]; };
layout(std430, binding = 3) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = 4) writeonly buffer Values { uint values[]; };
layout(std430, binding = 5) readonly buffer Touched { uint touched[]; };

layout(push_constant) uniform Push {
  uint count, tiles_x, depth_bits;
  float near_plane, far_plane;
  uint width, height;
} pc;

void main() {
  const uint g = nf_linear_index();
  if (g >= pc.count || proj[g * 12u + 11u] == 0.0) return;
  const uint top = (pc.depth_bits >= 32u ? 0xffffffffu : (1u << pc.depth_bits) - 1u);
  const float f = clamp((proj[g * 12u + 6u] - pc.near_plane) / (pc.far_plane - pc.near_plane), 0.0, 1.0);
  const uint depth = min(uint(f * float(top)), top);
  const uint r0 = rects[2u * g], r1 = rects[2u * g + 1u];
  const vec2 mean = vec2(proj[g * 12u], proj[g * 12u + 1u]);
  const vec3 conic = vec3(proj[g * 12u + 2u], proj[g * 12u + 3u], proj[g * 12u + 4u]);
  const float opacity = proj[g * 12u + 5u];
  uint at = offsets[g];
  const uint stop = at + touched[g];
  for (uint y = r0 >> 16; y <= (r1 >> 16); ++y)
    for (uint x = r0 & 0xffffu; x <= (r1 & 0xffffu); ++x) {
      vec2 lo, hi;
      nf_tile_rect(x, y, NF_TILE, pc.width, pc.height, lo, hi);
      if (at < stop && nf_ellipse_reaches(mean, conic, opacity, lo, hi)) {
        keys[at] = ((y * pc.tiles_x + x) << pc.depth_bits) | depth;
        values[at] = g;
        ++at;
      }
    }
  for (; at < stop; ++at) {
    keys[at] = 0xffffffffu;
    values[at] = g;
  }
}
