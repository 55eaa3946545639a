#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, pass 2c: every Gaussian writes one tile-index key per tile it reaches (the
// tiles rasterize_project found: its bits, or its whole square beyond 32 tiles) at the offset that
// the scan of the counts in depth order (rasterize_sorted_counts) gave its depth rank; the value is
// the Gaussian's index. A stable sort by tile then leaves every tile's list front to back.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Proj { float proj[]; };
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };  // per depth rank
layout(std430, binding = 2) readonly buffer Rects { uint rects[]; };
layout(std430, binding = 3) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = 4) writeonly buffer Values { uint values[]; };
layout(std430, binding = 5) readonly buffer Touched { uint touched[]; };
layout(std430, binding = 6) readonly buffer Rank { uint rank_of[]; };  // depth rank of each Gaussian

layout(push_constant) uniform Push {
  uint count, tiles_x;
} pc;

void main() {
  const uint g = nf_linear_index();
  if (g >= pc.count || touched[g] == 0u) return;
  const uint r0 = rects[3u * g], r1 = rects[3u * g + 1u], bits = rects[3u * g + 2u];
  const uint x0 = r0 & 0xffffu, y0 = r0 >> 16, w = (r1 & 0xffffu) - x0 + 1u;
  const uint area = w * ((r1 >> 16) - y0 + 1u);
  uint at = offsets[rank_of[g]];
  // do-while: rasterize_fwd.comp says why. A Gaussian here has at least one tile.
  if (area <= 32u) {
    uint left = bits;
    do {
      const uint i = uint(findLSB(left));
      left &= left - 1u;
      keys[at] = (y0 + i / w) * pc.tiles_x + x0 + i % w;
      values[at] = g;
      ++at;
    } while (left != 0u);
  } else {
    uint i = 0u;
    do {
      keys[at] = (y0 + i / w) * pc.tiles_x + x0 + i % w;
      values[at] = g;
      ++at;
    } while (++i < area);
  }
}
