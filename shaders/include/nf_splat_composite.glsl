// Shared pieces of the compositing kernels of strand rasterisation: one workgroup per tile
// (nf_splat_tile.glsl), invocation i shades pixel (i % NF_TILE, i / NF_TILE) of it; Gaussians are
// staged in shared memory one per invocation at a time. Constants and rules as in engine/splat/rasterizer_ref.hpp (composite, composite_adjoint).
#ifndef NF_SPLAT_COMPOSITE_GLSL
#define NF_SPLAT_COMPOSITE_GLSL
#include "nf_splat_tile.glsl"

const float ALPHA_MIN = 1.0 / 255.0, ALPHA_MAX = 0.99, T_MIN = 5e-5;  // see rasterizer_ref.hpp
const uint BATCH = 16u;

shared vec4 s_mean_opacity[BATCH];  // u, v, opacity, depth
shared vec3 s_conic[BATCH];
shared vec3 s_attr[BATCH];          // orientation x, y, confidence
shared uint s_id[BATCH];

void nf_stage_gaussian(uint slot, uint id) {
  const uint b = id * 12u;
  s_mean_opacity[slot] = vec4(proj[b + 0u], proj[b + 1u], proj[b + 5u], proj[b + 6u]);
  s_conic[slot] = vec3(proj[b + 2u], proj[b + 3u], proj[b + 4u]);
  s_attr[slot] = vec3(proj[b + 7u], proj[b + 8u], proj[b + 9u]);
  s_id[slot] = id;
}

// exp's argument for a pixel centre q (<= 0 inside the Gaussian's support).
float nf_power(uint slot, vec2 q) {
  const vec2 d = q - s_mean_opacity[slot].xy;
  const vec3 c = s_conic[slot];
  return -0.5 * (c.x * d.x * d.x + 2.0 * c.y * d.x * d.y + c.z * d.y * d.y);
}

// Opacity at a pixel: 0 below the cut-off, continuous above it (rasterizer_ref.hpp explains).
const float POWER_MIN = -5.5413;  // ln(1/255): below it alpha < 1/255 whatever the opacity (<= 1)

float nf_alpha(uint slot, float power) {
  if (power > 0.0 || power < POWER_MIN) return 0.0;  // most pairs of a tile: skip the exp
  const float raw = min(ALPHA_MAX, s_mean_opacity[slot].z * exp(power));
  return raw < ALPHA_MIN ? 0.0 : (raw - ALPHA_MIN) / (1.0 - ALPHA_MIN);
}

#endif
