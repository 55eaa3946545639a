#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, pass 4: front-to-back compositing per tile. Writes the 5 channels (alpha,
// orientation x/y, confidence, depth; planar), the final transmittance and how far into the tile's
// list each pixel went (for the backward pass). Gaussians behind the body depth are skipped. How
// Gaussians reach pixels (subgroup batches, ballot, broadcast): nf_splat_composite.glsl.
// A pass walks list positions [walk_begin, walk_end) of every tile: on a device whose loops end
// after a fixed number of iterations (lavapipe) long lists are walked in several passes, each
// resuming from the state the last one left in the outputs (the pixel's done flag rides in `last`).

layout(constant_id = 0) const uint WG = 64;  // NF_TILE^2 / PPI
layout(constant_id = 1) const uint PPI = 1;  // pixels per invocation: a column of PPI rows
layout(constant_id = 2) const bool IN_PASSES = false;  // lists walked in several passes (compiled out if not)
layout(local_size_x_id = 0) in;
#extension GL_EXT_control_flow_attributes : require
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Proj { vec4 proj4[]; };  // 3 per Gaussian
layout(std430, binding = 1) readonly buffer Values { uint values[]; };  // sorted Gaussian ids
layout(std430, binding = 2) readonly buffer Ranges { uint ranges[]; };
layout(std430, binding = 3) readonly buffer Body { float body_depth[]; };  // H * W, or 1 float (none)
layout(std430, binding = 4) buffer Image { float image[]; };     // 5 planes of H * W
layout(std430, binding = 5) buffer FinalT { float final_t[]; };
layout(std430, binding = 6) buffer Last { uint last[]; };        // list positions used | NF_WALK_DONE
layout(std430, binding = 7) readonly buffer LongTiles { uint long_tiles[]; };  // tiles the passes after the first visit

layout(push_constant) uniform Push {
  uint width, height, tiles_x, has_body;
  uint walk_begin, walk_end;  // list positions (from the tile's start) this pass walks
  uint long_count;            // passes after the first: one workgroup per tile of long_tiles
  float depth_slack;          // how far a Gaussian's depth may lie before its sort key's (quantisation)
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
  uint tile = nf_linear_group();
  if (IN_PASSES && pc.walk_begin > 0u) {
    if (tile >= pc.long_count) return;
    tile = long_tiles[tile];
  }
  if (tile >= pc.tiles_x * ((pc.height + NF_TILE - 1u) / NF_TILE)) return;  // folded dispatches may overshoot
  const uint ty = tile / pc.tiles_x, tx = tile - ty * pc.tiles_x;
  const uint lx = gl_LocalInvocationID.x % NF_TILE, ly0 = (gl_LocalInvocationID.x / NF_TILE) * PPI;
  const uint px = tx * NF_TILE + lx;
  const uint start = ranges[2u * tile], end = ranges[2u * tile + 1u];
  // A list that ended in an earlier pass leaves its pixels as that pass wrote them.
  if (IN_PASSES && pc.walk_begin > 0u && end - start <= pc.walk_begin) return;
  const uint plane = pc.width * pc.height;
  [[unroll]] for (uint r = 0u; r < PPI; ++r) {
    const uint py = ty * NF_TILE + ly0 + r;
    const bool inside = px < pc.width && py < pc.height;
    const uint pix = inside ? py * pc.width + px : 0u;
    occluder[r] = (inside && pc.has_body != 0u) ? body_depth[pix] : 3.0e38;
    q[r] = vec2(px, py) + 0.5;
    T[r] = 1.0;
    acc[r] = vec4(0.0);
    done[r] = !inside;
    last_used[r] = 0u;
    if (IN_PASSES && inside && pc.walk_begin > 0u) {  // resume where the last pass stopped
      T[r] = final_t[pix];
      acc[r] = vec4(image[plane + pix], image[2u * plane + pix], image[3u * plane + pix], image[4u * plane + pix]);
      done[r] = (last[pix] & NF_WALK_DONE) != 0u;
      last_used[r] = last[pix] & ~NF_WALK_DONE;
    }
  }
  vec2 lo, hi;
  nf_subgroup_rect(q[0], q[PPI - 1u], lo, hi);
  // The deepest body behind a pixel still compositing (+inf where no body is seen; a NaN depth
  // hides nothing in composite, so it counts as none here too). Without a body nothing stops early.
  const bool body_stops = pc.has_body != 0u;
  float deepest = -3.0e38;
  if (body_stops) {
    [[unroll]] for (uint r = 0u; r < PPI; ++r)
      if (!done[r]) deepest = max(deepest, isnan(occluder[r]) ? 3.0e38 : occluder[r]);
    deepest = subgroupMax(deepest) + pc.depth_slack;
  }
  const uint stop = start + min(end - start, pc.walk_end);
  const uint lane = gl_SubgroupInvocationID, lanes = nf_active_lanes();
  // Loops are do-while on purpose: on lavapipe a while or for loop runs its body once more, masked,
  // before it leaves (its exit test sits at the top); a do-while tests at the bottom.
  uint first = start + pc.walk_begin;
  if (first < stop) do {
    if (subgroupAll(all_done())) break;
    const uint n = min(lanes, stop - first);
    const NfGaussianLanes mine = nf_load_gaussian(values[first + min(lane, n - 1u)]);
    // The list runs front to back: once a whole batch lies behind every pixel's body, so does the
    // rest of it, and nothing there would be composited.
    if (body_stops && subgroupMin(mine.b.z) > deepest) break;
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
  } while (first < stop);
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
    last[pix] = last_used[r] | (done[r] ? NF_WALK_DONE : 0u);
  }
}
