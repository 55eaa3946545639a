#version 460
#extension GL_GOOGLE_include_directive : require
// Each strand point's grid cell (clamped to the grid) as a sort key, its index as the value.
// Host wrapper: engine/fur/strand_chamfer.cpp.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };
layout(std430, binding = 1) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = 2) writeonly buffer Values { uint values[]; };

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
  keys[j] = (uint(c.z) * uint(pc.ny) + uint(c.y)) * uint(pc.nx) + uint(c.x);
  values[j] = j;
}
