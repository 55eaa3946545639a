// Whether a projected Gaussian reaches alpha >= 1/255 at any pixel centre of a rectangle: the exact
// minimum of its conic's quadratic form over the rectangle against the level where
// opacity * exp(-q/2) = 1/255 (with a margin for rounding). A Gaussian it rejects contributes
// nothing there (alpha 0) and receives no gradient. Used for tiles (rasterize_project) and for the
// pixels of one subgroup (nf_splat_composite.glsl).
#ifndef NF_SPLAT_REACH_GLSL
#define NF_SPLAT_REACH_GLSL

// Smallest d^T C d over dy in [lo, hi] at fixed dx, for C = [[a, b], [b, c]] positive definite.
float nf_edge_min(float dx, float lo, float hi, float a, float b, float c) {
  const float dy = clamp(-b * dx / c, lo, hi);
  const float q = a * dx * dx + 2.0 * b * dx * dy + c * dy * dy;
  return q;
}

// lo, hi: the first and last pixel centres of the rectangle; conic = (a, b, c).
bool nf_ellipse_reaches(vec2 mean, vec3 conic, float opacity, vec2 lo, vec2 hi) {
  if (!(opacity * 255.0 > 1.0)) return false;
  const float level = 2.0 * log(opacity * 255.0) * 1.001 + 1e-4;
  const vec2 d0 = lo - mean, d1 = hi - mean;
  if (d0.x <= 0.0 && d1.x >= 0.0 && d0.y <= 0.0 && d1.y >= 0.0) return true;  // the mean is inside
  const float a = conic.x, b = conic.y, c = conic.z;
  const float qx = min(nf_edge_min(d0.x, d0.y, d1.y, a, b, c), nf_edge_min(d1.x, d0.y, d1.y, a, b, c));
  const float qy = min(nf_edge_min(d0.y, d0.x, d1.x, c, b, a), nf_edge_min(d1.y, d0.x, d1.x, c, b, a));
  return min(qx, qy) <= level;
}

// Pixel-centre rectangle of tile (tx, ty), clipped to the image.
void nf_tile_rect(uint tx, uint ty, uint tile_size, uint width, uint height, out vec2 lo, out vec2 hi) {
  lo = vec2(tx * tile_size, ty * tile_size) + 0.5;
  hi = vec2(min((tx + 1u) * tile_size, width) - 1u, min((ty + 1u) * tile_size, height) - 1u) + 0.5;
}

#endif
