#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, pass 2b: the tile counts of the Gaussians in depth order, for the scan that
// places their tile entries, and each Gaussian's depth rank (rasterize_keys reads the Gaussians in
// index order, which keeps its reads sequential, and writes each one's entries at its rank's offset).

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Order { uint order[]; };
layout(std430, binding = 1) readonly buffer Touched { uint touched[]; };
layout(std430, binding = 2) writeonly buffer SortedTouched { uint sorted_touched[]; };
layout(std430, binding = 3) writeonly buffer Rank { uint rank_of[]; };

layout(push_constant) uniform Push {
  uint count;
} pc;

void main() {
  const uint r = nf_linear_index();
  if (r >= pc.count) return;
  const uint g = order[r];
  sorted_touched[r] = touched[g];
  rank_of[g] = r;
}
