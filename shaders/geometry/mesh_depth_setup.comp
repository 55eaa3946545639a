#version 460
#extension GL_GOOGLE_include_directive : require
// Body depth map, pass 2, one invocation per triangle: the pixel box to test. A triangle behind the
// near plane gets none; one crossing it is clipped against depth = near (up to 4 vertices) and the
// box is that of the projected clipped polygon, widened by `margin` pixels for rounding. A box that
// fits one tile is rasterised here at once; a bigger one is left to mesh_depth_raster as
// ceil(w / tile) * ceil(h / tile) work items. Host wrapper: engine/geometry/mesh_depth.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Triangles { uint triangles[]; };  // this chunk: T * 3
layout(std430, binding = 1) readonly buffer Camera { float cam[]; };          // V * 3, camera space
layout(std430, binding = 2) writeonly buffer Boxes { uvec4 boxes[]; };        // x0, y0, x1, y1 (inclusive)
layout(std430, binding = 3) writeonly buffer Counts { uint counts[]; };       // work items per triangle
layout(std430, binding = 4) buffer Depth { uint depth[]; };                   // H * W float bits
#include "nf_mesh_depth.glsl"

vec3 vertex(uint v) { return vec3(cam[3u * v], cam[3u * v + 1u], cam[3u * v + 2u]); }

void main() {
  const uint f = nf_linear_index();
  if (f >= pc.triangles) return;
  const vec3 v[3] = vec3[3](vertex(triangles[3u * f]), vertex(triangles[3u * f + 1u]), vertex(triangles[3u * f + 2u]));
  precise float umin = 1e30, umax = -1e30, vmin = 1e30, vmax = -1e30;
  uint n = 0u;
  if (-v[0].z >= pc.near && -v[1].z >= pc.near && -v[2].z >= pc.near) {
    // In front of the near plane (the common case): project the vertices.
    for (uint k = 0u; k < 3u; ++k) {
      precise float depth_p = max(-v[k].z, pc.near);
      precise float u = pc.cx + (pc.fx * v[k].x) / depth_p, w = pc.cy - (pc.fy * v[k].y) / depth_p;
      umin = min(umin, u), umax = max(umax, u), vmin = min(vmin, w), vmax = max(vmax, w);
    }
    n = 3u;
  } else {
    // Clip against depth = -z >= near (Sutherland-Hodgman on one plane), projecting as we go.
    for (uint k = 0u; k < 3u; ++k) {
      const vec3 a = v[k], b = v[(k + 1u) % 3u];
      precise float da = -a.z - pc.near, db = -b.z - pc.near;
      for (uint j = 0u; j < 2u; ++j) {
        precise vec3 p;
        if (j == 0u) {
          if (!(da >= 0.0)) continue;
          p = a;
        } else {
          if ((da >= 0.0) == (db >= 0.0)) continue;
          precise float s = da / (da - db);
          p = vec3(a.x + (b.x - a.x) * s, a.y + (b.y - a.y) * s, a.z + (b.z - a.z) * s);
        }
        precise float depth_p = max(-p.z, pc.near);  // clipped vertices sit on the plane
        precise float u = pc.cx + (pc.fx * p.x) / depth_p, w = pc.cy - (pc.fy * p.y) / depth_p;
        umin = min(umin, u), umax = max(umax, u), vmin = min(vmin, w), vmax = max(vmax, w);
        ++n;
      }
    }
  }
  uint count = 0u;
  uvec4 box = uvec4(0u);
  if (n > 0u) {
    // Pixel x is tested when its centre x + 0.5 lies in [umin - margin, umax + margin].
    const float W = float(pc.width), H = float(pc.height);
    precise float x0 = ceil((clamp(umin, -4.0, W + 4.0) - 0.5) - pc.margin);
    precise float x1 = floor((clamp(umax, -4.0, W + 4.0) - 0.5) + pc.margin);
    precise float y0 = ceil((clamp(vmin, -4.0, H + 4.0) - 0.5) - pc.margin);
    precise float y1 = floor((clamp(vmax, -4.0, H + 4.0) - 0.5) + pc.margin);
    const int ix0 = max(int(x0), 0), ix1 = min(int(x1), int(pc.width) - 1);
    const int iy0 = max(int(y0), 0), iy1 = min(int(y1), int(pc.height) - 1);
    if (ix0 <= ix1 && iy0 <= iy1) {
      box = uvec4(ix0, iy0, ix1, iy1);
      const uint tiles_x = (box.z - box.x) / pc.tile + 1u, tiles_y = (box.w - box.y) / pc.tile + 1u;
      if (tiles_x * tiles_y == 1u)
        nf_mesh_depth_box(v[0], v[1], v[2], box.x, box.y, box.z, box.w);
      else
        count = tiles_x * tiles_y;
    }
  }
  boxes[f] = box;
  counts[f] = count;
}
