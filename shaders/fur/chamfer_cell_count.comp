#version 460
#extension GL_GOOGLE_include_directive : require
// Counting sort of the strand points by grid cell, step 1: each point's cell (clamped to the grid)
// and its slot among the cell's points, taken with an atomic add on the cell's count. The slots'
// order within a cell varies from run to run; nothing depends on it (the query breaks ties by the
// point's index). Host wrapper: engine/fur/strand_chamfer.cpp.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };
layout(std430, binding = 1) writeonly buffer Cells { uint cells[]; };
layout(std430, binding = 2) writeonly buffer Slots { uint slots[]; };
layout(std430, binding = 3) buffer Counts { uint counts[]; };  // zero-filled by the host

layout(push_constant) uniform Push {
  uint count;
  int nx, ny, nz;
  float ox, oy, oz, cell;
  int max_rings;  // shared push block with chamfer_query (unused here)
} pc;

void main() {
  const uint j = nf_linear_index();
  if (j >= pc.count) return;
  const vec3 p = vec3(points[3u * j], points[3u * j + 1u], points[3u * j + 2u]);
  const ivec3 c = clamp(ivec3(floor((p - vec3(pc.ox, pc.oy, pc.oz)) / pc.cell)), ivec3(0), ivec3(pc.nx, pc.ny, pc.nz) - 1);
  const uint key = (uint(c.z) * uint(pc.ny) + uint(c.y)) * uint(pc.nx) + uint(c.x);
  cells[j] = key;
  slots[j] = atomicAdd(counts[key], 1u);
}
