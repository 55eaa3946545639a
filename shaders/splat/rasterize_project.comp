#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, pass 1: every segment becomes a screen-space Gaussian (12 floats, see
// nf_splat_project.glsl) and finds the tiles it reaches: tiles of its 3.5-sigma square that its
// ellipse at alpha 1/255 meets (nf_splat_reach.glsl; a fur segment's square holds 2-3 times the
// tiles its ellipse meets). It stores the square and, when the square has at most 32 tiles, a
// bit per tile reached (beyond that every tile of the square counts), so that rasterize_keys
// writes exactly the tiles counted here. One invocation per segment. Host: engine/splat/rasterizer.cpp.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_splat_camera.glsl"
#include "nf_splat_project.glsl"
#include "nf_splat_tile.glsl"
#include "nf_splat_reach.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };     // strands * L * 3
layout(std430, binding = 1) readonly buffer Conf { float conf[]; };         // per segment
layout(std430, binding = 2) writeonly buffer Proj { float proj[]; };        // per segment * 12
layout(std430, binding = 3) writeonly buffer Touched { uint touched[]; };   // tiles per segment
layout(std430, binding = 4) writeonly buffer Rects { uint rects[]; };       // x0 | y0 << 16, x1 | y1 << 16, tile bits

void main() {
  const uint segs = pc.points_per_strand - 1u;
  const uint g = nf_linear_index();
  if (g >= pc.strands * segs) return;
  const uint strand = g / segs, l = g - strand * segs;
  const uint i0 = (strand * pc.points_per_strand + l) * 3u;
  const vec3 p0 = vec3(points[i0], points[i0 + 1u], points[i0 + 2u]);
  const vec3 p1 = vec3(points[i0 + 3u], points[i0 + 4u], points[i0 + 5u]);
  float o[12];
  const bool valid = nf_project_segment(p0, p1, conf[g], o);
  for (uint i = 0u; i < P_FLOATS; ++i) proj[g * P_FLOATS + i] = o[i];
  uint count = 0u, r0 = 0u, r1 = 0u, bits = 0u;
  if (valid) {
    const int ntx = int((pc.width + NF_TILE - 1u) / NF_TILE), nty = int((pc.height + NF_TILE - 1u) / NF_TILE);
    const float r = o[P_RADIUS];
    const int x0 = clamp(int(floor((o[P_U] - r) / float(NF_TILE))), 0, ntx - 1), x1 = clamp(int(floor((o[P_U] + r) / float(NF_TILE))), 0, ntx - 1);
    const int y0 = clamp(int(floor((o[P_V] - r) / float(NF_TILE))), 0, nty - 1), y1 = clamp(int(floor((o[P_V] + r) / float(NF_TILE))), 0, nty - 1);
    const vec2 mean = vec2(o[P_U], o[P_V]);
    const vec3 conic = vec3(o[P_CA], o[P_CB], o[P_CC]);
    const int w = x1 - x0 + 1, area = w * (y1 - y0 + 1);
    if (area <= 32) {
      // do-while: rasterize_fwd.comp says why. The square is never empty.
      int i = 0;
      do {
        const int y = y0 + i / w, x = x0 + i % w;
        vec2 lo, hi;
        nf_tile_rect(uint(x), uint(y), NF_TILE, pc.width, pc.height, lo, hi);
        if (nf_ellipse_reaches(mean, conic, o[P_OPACITY], lo, hi)) bits |= 1u << uint(i);
      } while (++i < area);
      count = uint(bitCount(bits));
    } else {
      count = uint(area);
    }
    r0 = uint(x0) | (uint(y0) << 16);
    r1 = uint(x1) | (uint(y1) << 16);
  }
  touched[g] = count;
  rects[3u * g] = r0;
  rects[3u * g + 1u] = r1;
  rects[3u * g + 2u] = bits;
}
