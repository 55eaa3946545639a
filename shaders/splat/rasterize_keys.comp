#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, pass 2c: every Gaussian writes one tile-index key per tile it reaches (the
// tiles rasterize_project counted, by the same test) at the offset that the scan of the counts in
// depth order (rasterize_sorted_counts) gave its depth rank; the value is the Gaussian's index. A stable sort
// by tile then leaves every tile's list front to back. Should the two passes ever disagree, the
// count wins: no slot past it is written and unused slots get the key `tiles`, past every tile.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_splat_tile.glsl"
#include "nf_splat_reach.glsl"

layout(std430, binding = 0) readonly buffer Proj { float proj[]; };
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };  // per depth rank
layout(std430, binding = 2) readonly buffer Rects { uint rects[]; };
layout(std430, binding = 3) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = 4) writeonly buffer Values { uint values[]; };
layout(std430, binding = 5) readonly buffer Touched { uint touched[]; };
layout(std430, binding = 6) readonly buffer Rank { uint rank_of[]; };  // depth rank of each Gaussian

layout(push_constant) uniform Push {
  uint count, tiles_x, tiles;
  uint width, height;
} pc;

void main() {
  const uint g = nf_linear_index();
  if (g >= pc.count || touched[g] == 0u) return;
  const uint r0 = rects[2u * g], r1 = rects[2u * g + 1u];
  const vec2 mean = vec2(proj[g * 12u], proj[g * 12u + 1u]);
  const vec3 conic = vec3(proj[g * 12u + 2u], proj[g * 12u + 3u], proj[g * 12u + 4u]);
  const float opacity = proj[g * 12u + 5u];
  uint at = offsets[rank_of[g]];
  const uint stop = at + touched[g];
  // do-while: rasterize_fwd.comp says why. The rectangle is never empty.
  uint y = r0 >> 16;
  do {
    uint x = r0 & 0xffffu;
    do {
      vec2 lo, hi;
      nf_tile_rect(x, y, NF_TILE, pc.width, pc.height, lo, hi);
      if (at < stop && nf_ellipse_reaches(mean, conic, opacity, lo, hi)) {
        keys[at] = y * pc.tiles_x + x;
        values[at] = g;
        ++at;
      }
    } while (++x <= (r1 & 0xffffu));
  } while (++y <= (r1 >> 16));
  while (at < stop) {  // only if the two passes disagreed
    keys[at] = pc.tiles;
    values[at] = g;
    ++at;
  }
}
