#version 460
#extension GL_GOOGLE_include_directive : require
// Counting sort of the strand points by grid cell, step 2 (after the scan of the cells' counts):
// each point written to its cell's run with its index in the fourth lane (float bits), so that a
// query's walk over a cell reads one contiguous run of 16-byte records instead of gathering every
// point through its index. Host wrapper: engine/fur/strand_chamfer.cpp.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };
layout(std430, binding = 1) readonly buffer Cells { uint cells[]; };
layout(std430, binding = 2) readonly buffer Slots { uint slots[]; };
layout(std430, binding = 3) readonly buffer Start { uint start[]; };  // the counts' exclusive scan
layout(std430, binding = 4) writeonly buffer Records { vec4 records[]; };

layout(push_constant) uniform Push {
  uint count;
} pc;

void main() {
  const uint j = nf_linear_index();
  if (j >= pc.count) return;
  records[start[cells[j]] + slots[j]] = vec4(points[3u * j], points[3u * j + 1u], points[3u * j + 2u], uintBitsToFloat(j));
}
