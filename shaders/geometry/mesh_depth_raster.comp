#version 460
#extension GL_GOOGLE_include_directive : require
// Body depth map, pass 3: the triangles whose box spans several tiles. A fixed grid of invocations
// strides over the (triangle, tile) work items numbered by the exclusive scan of the per-triangle
// item counts; each item tests at most tile^2 pixel centres (nf_mesh_depth_box), so a
// screen-filling triangle is spread over the whole grid. Host wrapper: engine/geometry/mesh_depth.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Triangles { uint triangles[]; };  // this chunk: T * 3
layout(std430, binding = 1) readonly buffer Camera { float cam[]; };          // V * 3, camera space
layout(std430, binding = 2) readonly buffer Boxes { uvec4 boxes[]; };
layout(std430, binding = 3) readonly buffer Offsets { uint offsets[]; };      // exclusive scan of counts
layout(std430, binding = 4) readonly buffer Total { uint total; };            // all items of the chunk
layout(std430, binding = 5) buffer Depth { uint depth[]; };                   // H * W float bits
#include "nf_mesh_depth.glsl"

vec3 vertex(uint v) { return vec3(cam[3u * v], cam[3u * v + 1u], cam[3u * v + 2u]); }

void main() {
  const uint items = total;
  for (uint item = nf_linear_index(); item < items; item += pc.stride) {
    // The triangle: the last f with offsets[f] <= item (triangles without items share offsets).
    uint lo = 0u, hi = pc.triangles;
    while (hi - lo > 1u) {
      const uint mid = (lo + hi) / 2u;
      if (offsets[mid] <= item) lo = mid; else hi = mid;
    }
    const uint f = lo, local = item - offsets[f];
    const uvec4 box = boxes[f];
    const uint tiles_x = (box.z - box.x) / pc.tile + 1u;
    const uint ty = local / tiles_x, tx = local - ty * tiles_x;
    const uint x0 = box.x + tx * pc.tile, y0 = box.y + ty * pc.tile;
    const uint x1 = min(x0 + pc.tile - 1u, box.z), y1 = min(y0 + pc.tile - 1u, box.w);
    nf_mesh_depth_box(vertex(triangles[3u * f]), vertex(triangles[3u * f + 1u]), vertex(triangles[3u * f + 2u]),
                      x0, y0, x1, y1);
  }
}
