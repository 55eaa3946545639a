#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, pass 4: front-to-back compositing per tile. Writes the 5 channels (alpha,
// orientation x/y, confidence, depth; planar), the final transmittance and how far into the tile's
// list each pixel went (for the backward pass). Gaussians behind the body depth are skipped. How
// Gaussians reach pixels (subgroup batches, ballot, broadcast): nf_splat_composite.glsl.

layout(constant_id = 0) const uint WG = 64;  // NF_TILE^2 / PPI
layout(constant_id = 1) const uint PPI = 1;  // pixels per invocation: a column of PPI rows
layout(local_size_x_id = 0) in;
#extension GL_EXT_control_flow_attributes : require
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Proj { vec4 proj4[]; };  // 3 per Gaussian
layout(std430, binding = 1) readonly buffer Values { uint values[]; };  // sorted Gaussian ids
layout(std430, binding = 2) readonly buffer Ranges { uint ranges[]; };
layout(std430, binding = 3) readonly buffer Body { float body_depth[]; };  // H * W, or 1 float (none)
layout(std430, binding = 4) writeonly buffer Image { float image[]; };     // 5 planes of H * W
layout(std430, binding = 5) writeonly buffer FinalT { float final_t[]; };
layout(std430, binding = 6) writeonly buffer Last { uint last[]; };

layout(push_constant) uniform Push {
  uint width, height, tiles_x, has_body;
} pc;

#include "nf_splat_composite.glsl"

// Per-pixel compositing state of this invocation's PPI pixels.
float T[PPI];
vec4 acc[PPI];  // orientation x, y, confidence, depth
bool done[PPI];
uint last_used[PPI];
float occluder[PPI];
vec2 q[PPI];

void composite(const NfGaussian g, uint position) {
  [[unroll]] for (uint r = 0u; r < PPI; ++r) {
    if (done[r] || g.depth > occluder[r]) continue;
    const float alpha = nf_alpha_of(g, nf_power_of(g, q[r]));
    if (alpha <= 0.0) continue;
    const float next = T[r] * (1.0 - alpha);
    if (next < T_MIN) {
      done[r] = true;
      continue;
    }
    acc[r] += alpha * T[r] * vec4(g.attr, g.depth);
    T[r] = next;
    last_used[r] = position + 1u;
  }
}

bool all_done() {
  bool all = true;
  [[unroll]] for (uint r = 0u; r < PPI; ++r) all = all && done[r];
  return all;
}

void main() {
  const uint tile = nf_linear_group();
  if (tile >= pc.tiles_x * ((pc.height + NF_TILE - 1u) / NF_TILE)) return;  // folded dispatches may overshoot
  const uint ty = tile / pc.tiles_x, tx = tile - ty * pc.tiles_x;
  const uint lx = gl_LocalInvocationID.x % NF_TILE, ly0 = (gl_LocalInvocationID.x / NF_TILE) * PPI;
  const uint px = tx * NF_TILE + lx;
  [[unroll]] for (uint r = 0u; r < PPI; ++r) {
    const uint py = ty * NF_TILE + ly0 + r;
    const bool inside = px < pc.width && py < pc.height;
    occluder[r] = (inside && pc.has_body != 0u) ? body_depth[py * pc.width + px] : 3.0e38;
    q[r] = vec2(px, py) + 0.5;
    T[r] = 1.0;
    acc[r] = vec4(0.0);
    done[r] = !inside;
    last_used[r] = 0u;
  }
  vec2 lo, hi;
  nf_subgroup_rect(q[0], q[PPI - 1u], lo, hi);
  const uint start = ranges[2u * tile], end = ranges[2u * tile + 1u];
  const uint lane = gl_SubgroupInvocationID, lanes = nf_active_lanes();
  // Loops are do-while on purpose: on lavapipe a while or for loop runs its body once more, masked,
  // before it leaves (its exit test sits at the top); a do-while tests at the bottom.
  uint first = start;
  if (first < end) do {
    if (subgroupAll(all_done())) break;
    const uint n = min(lanes, end - first);
    const NfGaussianLanes mine = nf_load_gaussian(values[first + min(lane, n - 1u)]);
    const uvec4 reach = subgroupBallot(lane < n && nf_reaches(nf_unpack(mine), lo, hi));
    uint word = 0u;
    do {
      uint bits = reach[word];
      if (bits != 0u) do {  // front to back: lowest list position first
        const uint j = word * 32u + uint(findLSB(bits));
        bits &= bits - 1u;
        composite(nf_broadcast(mine, j), first + j - start);
      } while (bits != 0u);
      ++word;
    } while (word * 32u < n);
    first += lanes;
  } while (first < end);
  const uint plane = pc.width * pc.height;
  [[unroll]] for (uint r = 0u; r < PPI; ++r) {
    const uint py = ty * NF_TILE + ly0 + r;
    if (px >= pc.width || py >= pc.height) continue;
    const uint pix = py * pc.width + px;
    image[pix] = 1.0 - T[r];
    image[plane + pix] = acc[r].x;
    image[2u * plane + pix] = acc[r].y;
    image[3u * plane + pix] = acc[r].z;
    image[4u * plane + pix] = acc[r].w;
    final_t[pix] = T[r];
    last[pix] = last_used[r];
  }
}
