// Shared pieces of the compositing kernels of strand rasterisation: one workgroup per tile
// (nf_splat_tile.glsl), invocation i shades the PPI pixels (i % NF_TILE, (i / NF_TILE) * PPI + r),
// r < PPI, of it. Constants and rules as in engine/splat/rasterizer_ref.hpp (composite,
// composite_adjoint).
//
// How a tile's Gaussians reach its pixels: the list is walked in batches of one Gaussian per lane
// of a subgroup; every lane loads its Gaussian into registers, tests whether it can reach any pixel
// of the subgroup (nf_reaches), and a ballot of that test drives a loop that broadcasts only those
// Gaussians to all lanes: no shared memory and no barriers in that walk. On lavapipe this matters twice:
// a shared-memory read inside a loop is a per-lane loop of scalar loads even at a uniform address
// (a broadcast is one extract), and code under a branch runs for every lane anyway (masked), so
// the only work skipped is loop iterations that never start: a fur Gaussian covers a row or two
// of an 8x8 tile, and the ballot drops it from the other rows' subgroups. Needs
// `proj4` (the projected Gaussians as vec4, layout in nf_splat_project.glsl).
#ifndef NF_SPLAT_COMPOSITE_GLSL
#define NF_SPLAT_COMPOSITE_GLSL
#include "nf_splat_tile.glsl"
#include "nf_splat_reach.glsl"
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_arithmetic : require

const float ALPHA_MIN = 1.0 / 255.0, ALPHA_MAX = 0.99, T_MIN = 5e-5;  // see rasterizer_ref.hpp
const float POWER_MIN = -5.5413;  // ln(1/255): below it alpha < 1/255 whatever the opacity (<= 1)
const uint NF_WALK_DONE = 0x80000000u;  // in `last`: the pixel's walk has ended (it saturated)

// One projected Gaussian in registers.
struct NfGaussian {
  vec2 mean;
  vec3 conic;
  float opacity;
  float depth;
  vec3 attr;  // orientation x, y, confidence
};

// The three vec4 of one Gaussian, as one lane holds them.
struct NfGaussianLanes {
  vec4 a;  // u, v, conic a, conic b
  vec4 b;  // conic c, opacity, depth, orientation x
  vec4 c;  // orientation y, confidence, radius, valid
};

NfGaussianLanes nf_load_gaussian(uint id) {
  return NfGaussianLanes(proj4[3u * id], proj4[3u * id + 1u], proj4[3u * id + 2u]);
}

NfGaussian nf_unpack(NfGaussianLanes l) { return NfGaussian(l.a.xy, vec3(l.a.zw, l.b.x), l.b.y, l.b.z, vec3(l.b.w, l.c.xy)); }

// Lane `lane`'s Gaussian for every lane of the subgroup (lane is subgroup-uniform).
NfGaussian nf_broadcast(NfGaussianLanes l, uint lane) {
  return nf_unpack(NfGaussianLanes(subgroupBroadcast(l.a, lane), subgroupBroadcast(l.b, lane), subgroupBroadcast(l.c, lane)));
}

// exp's argument for a pixel centre q (<= 0 inside the Gaussian's support).
float nf_power_of(const NfGaussian g, vec2 q) {
  const vec2 d = q - g.mean;
  return -0.5 * (g.conic.x * d.x * d.x + 2.0 * g.conic.y * d.x * d.y + g.conic.z * d.y * d.y);
}

// Opacity at a pixel: 0 below the cut-off, continuous above it (rasterizer_ref.hpp explains).
float nf_alpha_of(const NfGaussian g, float power) {
  if (power > 0.0 || power < POWER_MIN) return 0.0;
  const float raw = min(ALPHA_MAX, g.opacity * exp(power));
  return raw < ALPHA_MIN ? 0.0 : (raw - ALPHA_MIN) / (1.0 - ALPHA_MIN);
}

// Whether the Gaussian can reach any pixel of the rectangle lo..hi (pixel centres).
bool nf_reaches(const NfGaussian g, vec2 lo, vec2 hi) { return nf_ellipse_reaches(g.mean, g.conic, g.opacity, lo, hi); }

// The pixel centres this subgroup shades, from each lane's first and last pixel (all its lanes
// are active where this is called).
void nf_subgroup_rect(vec2 first, vec2 last, out vec2 lo, out vec2 hi) {
  lo = vec2(subgroupMin(min(first.x, last.x)), subgroupMin(min(first.y, last.y)));
  hi = vec2(subgroupMax(max(first.x, last.x)), subgroupMax(max(first.y, last.y)));
}

// Active lanes in this subgroup: the batch size (a workgroup smaller than a subgroup fills part of
// one). Unlike nf_workgroup.glsl's nf_subgroup_lanes it needs no workgroup size.
uint nf_active_lanes() { return subgroupBallotBitCount(subgroupBallot(true)); }

#endif
