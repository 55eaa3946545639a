#version 460
#extension GL_GOOGLE_include_directive : require
// Each query's nearest strand point by a ring search over the grid of cells: rings of cells at
// Chebyshev distance r = 0, 1, ..., max_rings around the query's cell, stopping once the best
// distance is below r cells plus the query's distance to its own cell's nearest wall (every point
// of a farther ring is at least that far), so a match is exact and a query whose nearest point
// lies in its own cell, well inside it, visits that cell alone. A query whose nearest point lies
// farther than max_rings cells is unmatched (nearest = ~0u, dist2 = 0). The bound also keeps the
// invocation's work short: lavapipe's loop limiter counts the iterations of a loop and of every
// loop nested in it together and ends them past 65,535 without an error (docs/gpu-runtime.md), so
// the rings' cells (25^3 at the host's cap of 12 rings) and the points they hold must stay below
// that; 20 rings of empty cells (39^3) already came back unmatched. Ties go to the lowest point
// index, as in the reference. Host wrapper: engine/fur/strand_chamfer.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Queries { float queries[]; };
layout(std430, binding = 1) readonly buffer Records { vec4 records[]; };  // points by cell, index in w
layout(std430, binding = 2) readonly buffer Start { uint start[]; };
layout(std430, binding = 3) readonly buffer Counts { uint counts[]; };
layout(std430, binding = 4) writeonly buffer Nearest { uint nearest[]; };
layout(std430, binding = 5) writeonly buffer Dist2 { float dist2[]; };

layout(push_constant) uniform Push {
  uint count;
  int nx, ny, nz;
  float ox, oy, oz, cell;
  int max_rings;
} pc;

float best;
uint best_id;
vec3 x;

// Every point of one cell against the best so far.
void visit(int cx, int cy, int cz) {
  if (cx < 0 || cx >= pc.nx || cy < 0 || cy >= pc.ny || cz < 0 || cz >= pc.nz) return;
  const uint cell = (uint(cz) * uint(pc.ny) + uint(cy)) * uint(pc.nx) + uint(cx);
  const uint first = start[cell], e = first + counts[cell];
  for (uint i = first; i < e; ++i) {
    const vec4 record = records[i];
    const vec3 d = x - record.xyz;
    const float d2 = dot(d, d);
    if (d2 <= best) {
      const uint j = floatBitsToUint(record.w);
      if (d2 < best || j < best_id) {
        best = d2;
        best_id = j;
      }
    }
  }
}

void main() {
  const uint k = nf_linear_index();
  if (k >= pc.count) return;
  x = vec3(queries[3u * k], queries[3u * k + 1u], queries[3u * k + 2u]);
  const ivec3 dims = ivec3(pc.nx, pc.ny, pc.nz);
  const ivec3 c = clamp(ivec3(floor((x - vec3(pc.ox, pc.oy, pc.oz)) / pc.cell)), ivec3(0), dims - 1);
  const int rings = min(pc.max_rings, max(max(pc.nx, pc.ny), pc.nz));
  // How far the query lies inside its own cell: a point outside the cube of rings 0..r is at least
  // r cells plus this far away. Clamped to 0 on an axis where the query lies outside the grid, and
  // shortened by a little so that a point that floor() put in the next cell is still covered.
  // The margin covers floor()'s rounding of a point's cell: a small share of a cell, plus a few
  // float steps of the coordinates' magnitude (a box far from the origin).
  const vec3 origin = vec3(pc.ox, pc.oy, pc.oz), lo = origin + vec3(c) * pc.cell;
  const vec3 wall = max(min(x - lo, lo + pc.cell - x), vec3(0.0));
  const vec3 magnitude = abs(x) + abs(origin);
  const float margin = 1e-4 * pc.cell + 1e-6 * max(max(magnitude.x, magnitude.y), magnitude.z);
  const float inner = min(min(wall.x, wall.y), wall.z) - margin;
  best = uintBitsToFloat(0x7f800000u);  // +inf
  best_id = 0xffffffffu;
  for (int r = 0; r <= rings; ++r) {
    for (int dz = -r; dz <= r; ++dz)
      for (int dy = -r; dy <= r; ++dy) {
        if (abs(dz) == r || abs(dy) == r) {  // a face of the ring's cube: the whole row
          for (int dx = -r; dx <= r; ++dx) visit(c.x + dx, c.y + dy, c.z + dz);
        } else {  // inside the cube's faces: only the row's two ends belong to the ring
          visit(c.x - r, c.y + dy, c.z + dz);
          visit(c.x + r, c.y + dy, c.z + dz);
        }
      }
    const float bound = max(float(r) * pc.cell + inner, 0.0);
    if (best_id != 0xffffffffu && best < bound * bound) break;
  }
  const float reach = float(pc.max_rings) * pc.cell;
  const bool matched = best_id != 0xffffffffu && best <= reach * reach;
  nearest[k] = matched ? best_id : 0xffffffffu;
  dist2[k] = matched ? best : 0.0;
}
