#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, pass 3: after sorting, each tile's run of keys (tile indices) is
// [start, end); ranges must be zeroed before (tiles nobody touches stay empty).

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Keys { uint keys[]; };
layout(std430, binding = 1) writeonly buffer Ranges { uint ranges[]; };  // per tile: start, end

layout(push_constant) uniform Push {
  uint count, tiles;
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.count) return;
  const uint tile = keys[i];
  if (tile >= pc.tiles) return;  // a guard for the ranges buffer: keys are tile indices
  if (i == 0u || keys[i - 1u] != tile) ranges[2u * tile] = i;
  if (i + 1u == pc.count || keys[i + 1u] != tile) ranges[2u * tile + 1u] = i + 1u;
}
