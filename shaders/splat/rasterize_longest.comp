#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, after pass 3, on a device whose loops end after a fixed number of
// iterations: the longest tile list (how many passes the compositing walk takes) and the tiles
// whose list is longer than one pass (the only ones the later passes visit).

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Ranges { uint ranges[]; };  // per tile: start, end
layout(std430, binding = 1) buffer Stats { uint longest, long_count; };  // zeroed before
layout(std430, binding = 2) writeonly buffer LongTiles { uint long_tiles[]; };

layout(push_constant) uniform Push {
  uint tiles, chunk;
} pc;

void main() {
  const uint tile = nf_linear_index();
  if (tile >= pc.tiles) return;
  const uint length = ranges[2u * tile + 1u] - ranges[2u * tile];
  if (length > 0u) atomicMax(longest, length);
  if (length > pc.chunk) long_tiles[atomicAdd(long_count, 1u)] = tile;
}
