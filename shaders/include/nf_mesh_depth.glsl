// Body depth map (engine/geometry/mesh_depth.hpp): the push constants shared by the setup and raster
// kernels and the per-pixel test of one triangle over a pixel box. The CPU twin is in
// engine/geometry/mesh_depth.cpp; every float operation is `precise` and in the same order there, so
// both give the same bits (no FMA contraction).
// Include after declaring `layout(std430, binding = ...) buffer Depth { uint depth[]; };`.
#ifndef NF_MESH_DEPTH_GLSL
#define NF_MESH_DEPTH_GLSL

layout(push_constant) uniform Push {
  float fx, fy, inv_fx, inv_fy, cx, cy;
  float near;
  float margin;  // pixels added around a triangle's projected box (rounding slack)
  uint width, height;
  uint tile;     // work-item tile side in pixels
  uint triangles;
  uint stride;   // raster: invocations in the grid
} pc;

// Nearest depth >= near of the ray of every pixel centre of [x0, x1] x [y0, y1] (inclusive) that
// meets triangle (a, b, c), camera space; atomicMin on the float bits (valid for positive floats).
void nf_mesh_depth_box(vec3 a, vec3 b, vec3 c, uint x0, uint y0, uint x1, uint y1) {
  // Edge normals a x b, b x c, c x a written out: a neighbour's shared edge gives exact negatives.
  precise vec3 k0 = vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
  precise vec3 k1 = vec3(b.y * c.z - b.z * c.y, b.z * c.x - b.x * c.z, b.x * c.y - b.y * c.x);
  precise vec3 k2 = vec3(c.y * a.z - c.z * a.y, c.z * a.x - c.x * a.z, c.x * a.y - c.y * a.x);
  precise vec3 e1 = b - a, e2 = c - a;
  precise vec3 n = vec3(e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x);
  precise float num = (n.x * a.x + n.y * a.y) + n.z * a.z;
  for (uint y = y0; y <= y1; ++y) {
    precise float dy = -(((float(y) + 0.5) - pc.cy) * pc.inv_fy);
    for (uint x = x0; x <= x1; ++x) {
      precise float dx = ((float(x) + 0.5) - pc.cx) * pc.inv_fx;
      // Signed volumes d . (a x b) of the ray d = (dx, dy, -1) over the three edges.
      precise float s0 = (dx * k0.x + dy * k0.y) - k0.z;
      precise float s1 = (dx * k1.x + dy * k1.y) - k1.z;
      precise float s2 = (dx * k2.x + dy * k2.y) - k2.z;
      const bool inside = (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0);
      if (!inside) continue;
      precise float den = (n.x * dx + n.y * dy) - n.z;
      if (den == 0.0) continue;
      precise float t = num / den;  // the ray meets the plane at depth t
      const uint index = y * pc.width + x, bits = floatBitsToUint(t);
      // Read first: most candidates lose, and an atomic costs more than a load. Values only
      // decrease, so a stale read is too large, never too small: skipping on it is safe.
      if (t >= pc.near && !isinf(t) && bits < depth[index]) atomicMin(depth[index], bits);
    }
  }
}

#endif
