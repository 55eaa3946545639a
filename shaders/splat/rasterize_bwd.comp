#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, backward of pass 4: per tile, back to front over each pixel's contributors,
// the exact adjoint of compositing (engine/splat/rasterizer_ref.hpp, composite_adjoint). Gaussians
// reach pixels as in the forward (nf_splat_composite.glsl), batch by batch from the end of the
// list. A Gaussian's gradient is summed over its subgroup's pixels with subgroup sums (kept by the
// lane that loaded it), then over the tile's subgroups:
//   shared:   into shared memory with float atomics, then one global atomic per Gaussian and field
//             (GPUs with shared float atomics);
//   subgroup: one global atomic per subgroup, Gaussian and field, with no barriers, so that every
//             subgroup starts at its own pixels' last contributor. On CPU devices (lavapipe) this
//             is 1.5x faster: their shared atomics are per-lane loops and barriers switch
//             coroutines, while a tile there has only two subgroups.
// Like the forward, a pass undoes list positions [walk_begin, walk_end); passes run from the last
// to the first, handing each pixel's adjoint state (T_after, behind) on through `carry`.
//! variant shared -DNF_SHARED_SUMS
//! variant subgroup -DNF_SUBGROUP_SUMS
#extension GL_EXT_shader_atomic_float : require

layout(constant_id = 0) const uint WG = 64;  // NF_TILE^2 / PPI
layout(constant_id = 1) const uint PPI = 1;  // pixels per invocation: a column of PPI rows
layout(constant_id = 2) const bool IN_PASSES = false;  // lists walked in several passes (compiled out if not)
layout(local_size_x_id = 0) in;
#extension GL_EXT_control_flow_attributes : require
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Proj { vec4 proj4[]; };  // 3 per Gaussian
layout(std430, binding = 1) readonly buffer Values { uint values[]; };
layout(std430, binding = 2) readonly buffer Ranges { uint ranges[]; };
layout(std430, binding = 3) readonly buffer Body { float body_depth[]; };
layout(std430, binding = 4) readonly buffer FinalT { float final_t[]; };
layout(std430, binding = 5) readonly buffer Last { uint last[]; };  // list positions used | NF_WALK_DONE
layout(std430, binding = 6) readonly buffer GradImage { float grad_image[]; };  // 5 planes
layout(std430, binding = 7) buffer GradProj { float grad_proj[]; };             // per Gaussian * 12, accumulated
layout(std430, binding = 8) buffer Carry { float carry[]; };  // 6 planes of H * W: T_after, behind (walks of several passes)
layout(std430, binding = 9) readonly buffer LongTiles { uint long_tiles[]; };  // tiles the passes after the first visit

layout(push_constant) uniform Push {
  uint width, height, tiles_x, has_body;
  uint walk_begin, walk_end;  // list positions (from the tile's start) this pass undoes
  uint long_count;            // passes after the first: one workgroup per tile of long_tiles
  float depth_slack;          // (the forward's)
} pc;

#include "nf_splat_composite.glsl"

const uint FIELDS = 10u;  // u, v, conic a b c, opacity, depth, orientation x, y, confidence (proj order)

#ifdef NF_SHARED_SUMS
shared float s_grad[FIELDS][WG];  // per batch slot (a batch is at most one subgroup <= WG)
shared uint s_used;               // how far into the list any pixel of the tile went
#endif

// Per-pixel adjoint state of this invocation's PPI pixels.
float g[PPI][5];       // dL/d(alpha, orientation x, y, confidence, depth) of the pixel
float T_after[PPI];    // transmittance behind the Gaussian being undone
float behind[PPI][5];  // what the Gaussians behind it added to each channel
float occluder[PPI];
vec2 q[PPI];
bool inside[PPI];
uint my_last[PPI];     // list positions below it contributed

// Adds pixel r's gradient of the Gaussian at list position `position` to grad (nothing when it
// did not contribute) and steps the pixel back over it.
void undo(uint r, const NfGaussian gs, uint position, inout float grad[FIELDS], inout bool any) {
  bool contributes = inside[r] && position < my_last[r] && gs.depth <= occluder[r];
  float power = 0.0, alpha = 0.0;
  if (contributes) {
    power = nf_power_of(gs, q[r]);
    alpha = nf_alpha_of(gs, power);
    contributes = alpha > 0.0;
  }
  if (!contributes) return;
  any = true;
  const float one_minus = max(1e-6, 1.0 - alpha);
  const float Ti = T_after[r] / one_minus;
  const float w = alpha * Ti;
  const float f5[5] = float[5](1.0, gs.attr.x, gs.attr.y, gs.attr.z, gs.depth);
  grad[7] += g[r][1] * w;
  grad[8] += g[r][2] * w;
  grad[9] += g[r][3] * w;
  grad[6] += g[r][4] * w;
  float g_alpha = 0.0;
  [[unroll]] for (uint c = 0u; c < 5u; ++c) g_alpha += g[r][c] * (Ti * f5[c] - behind[r][c] / one_minus);
  [[unroll]] for (uint c = 0u; c < 5u; ++c) behind[r][c] += w * f5[c];
  T_after[r] = Ti;
  const float e = exp(power);
  if (gs.opacity * e < ALPHA_MAX) {  // the clamp passes no gradient
    const vec2 d = q[r] - gs.mean;
    const vec3 c = gs.conic;
    const float scale = 1.0 / (1.0 - ALPHA_MIN);
    const float g_power = g_alpha * scale * gs.opacity * e;
    grad[5] += g_alpha * scale * e;
    grad[2] += g_power * -0.5 * d.x * d.x;
    grad[3] += g_power * -d.x * d.y;
    grad[4] += g_power * -0.5 * d.y * d.y;
    grad[0] += g_power * (c.x * d.x + c.y * d.y);
    grad[1] += g_power * (c.y * d.x + c.z * d.y);
  }
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
  const uint plane = pc.width * pc.height;
  const uint start = ranges[2u * tile];
  uint lane_last = start;
  [[unroll]] for (uint r = 0u; r < PPI; ++r) {
    const uint py = ty * NF_TILE + ly0 + r;
    inside[r] = px < pc.width && py < pc.height;
    const uint pix = inside[r] ? py * pc.width + px : 0u;
    occluder[r] = (inside[r] && pc.has_body != 0u) ? body_depth[pix] : 3.0e38;
    q[r] = vec2(px, py) + 0.5;
    my_last[r] = inside[r] ? start + (last[pix] & ~NF_WALK_DONE) : start;
    lane_last = max(lane_last, my_last[r]);
    [[unroll]] for (uint c = 0u; c < 5u; ++c) {
      g[r][c] = inside[r] ? grad_image[c * plane + pix] : 0.0;
      behind[r][c] = 0.0;
    }
    T_after[r] = inside[r] ? final_t[pix] : 1.0;
  }
  vec2 lo, hi;
  nf_subgroup_rect(q[0], q[PPI - 1u], lo, hi);
  const uint lane = gl_SubgroupInvocationID, lanes = nf_active_lanes();
  // Where the forward stopped (every pixel opaque) nothing behind contributed: start there. In
  // dense fur most of a tile's list lies behind it.
  const uint subgroup_last = subgroupMax(lane_last);
#ifdef NF_SHARED_SUMS
  // The shared sums need every subgroup on the same batches: start at the tile's furthest point.
  // (Batches are one subgroup long; the subgroups of a workgroup have the same size, since it is a
  // whole number of them or part of one.)
  if (gl_LocalInvocationIndex == 0u) s_used = 0u;
  for (uint i = gl_LocalInvocationIndex; i < FIELDS * WG; i += WG) s_grad[i / WG][i % WG] = 0.0;
  barrier();
  if (subgroupElect()) atomicMax(s_used, subgroup_last - start);
  barrier();
  const uint count = s_used;
#else
  const uint count = subgroup_last - start;
#endif
  // This pass's share of the walk; nothing when the walk ends below it (the count is uniform over
  // the workgroup where barriers follow).
  if (count <= pc.walk_begin) return;
  const uint span = min(count, pc.walk_end) - pc.walk_begin;
  const uint end_used = start + pc.walk_begin + span;
  if (IN_PASSES) {
    // A pixel whose walk goes on past this pass had its positions behind undone by a later pass:
    // take up its state (decided per pixel, so that no two dispatches need the same subgroups).
    [[unroll]] for (uint r = 0u; r < PPI; ++r) {
      if (!inside[r] || my_last[r] - start <= pc.walk_end) continue;
      const uint pix = (ty * NF_TILE + ly0 + r) * pc.width + px;
      T_after[r] = carry[pix];
      [[unroll]] for (uint c = 0u; c < 5u; ++c) behind[r][c] = carry[(c + 1u) * plane + pix];
    }
  }
  // Loops are do-while on purpose: on lavapipe a while or for loop runs its body once more, masked,
  // before it leaves (its exit test sits at the top); a do-while tests at the bottom.
  uint done_count = 0u;
  do {
    const uint n = min(lanes, span - done_count);
    const uint first = end_used - done_count - n;  // this batch covers [first, first + n)
    const uint my_id = values[first + min(lane, n - 1u)];
    const NfGaussianLanes mine = nf_load_gaussian(my_id);
    const uvec4 reach = subgroupBallot(lane < n && first + lane < subgroup_last && nf_reaches(nf_unpack(mine), lo, hi));
    float sums[FIELDS];  // lane j: this subgroup's gradient of the batch's Gaussian j
    [[unroll]] for (uint f = 0u; f < FIELDS; ++f) sums[f] = 0.0;
    uint word = (n + 31u) / 32u;
    do {
      --word;
      uint bits = reach[word];
      if (bits != 0u) do {  // back to front: highest list position first
        const uint bit = uint(findMSB(bits));
        bits &= ~(1u << bit);
        const uint j = word * 32u + bit;
        const NfGaussian gs = nf_broadcast(mine, j);
        float grad[FIELDS];
        [[unroll]] for (uint f = 0u; f < FIELDS; ++f) grad[f] = 0.0;
        bool any = false;
        [[unroll]] for (uint r = 0u; r < PPI; ++r) undo(r, gs, first + j, grad, any);
        if (subgroupAny(any)) {
          [[unroll]] for (uint f = 0u; f < FIELDS; ++f) {
            const float s = subgroupAdd(grad[f]);
            if (lane == j) sums[f] = s;
          }
        }
      } while (bits != 0u);
    } while (word > 0u);
#ifdef NF_SHARED_SUMS
    if (lane < n)
      [[unroll]] for (uint f = 0u; f < FIELDS; ++f)
        if (sums[f] != 0.0) atomicAdd(s_grad[f][lane], sums[f]);
    barrier();
    if (gl_LocalInvocationIndex < n) {
      const uint slot = gl_LocalInvocationIndex, id = values[first + slot];
      [[unroll]] for (uint f = 0u; f < FIELDS; ++f) {
        const float v = s_grad[f][slot];
        if (v != 0.0) atomicAdd(grad_proj[id * 12u + f], v);
        s_grad[f][slot] = 0.0;
      }
    }
    barrier();
#else
    if (lane < n)
      [[unroll]] for (uint f = 0u; f < FIELDS; ++f)
        if (sums[f] != 0.0) atomicAdd(grad_proj[my_id * 12u + f], sums[f]);
#endif
    done_count += lanes;
  } while (done_count < span);
  if (IN_PASSES && pc.walk_begin > 0u) {  // an earlier pass goes on from here
    [[unroll]] for (uint r = 0u; r < PPI; ++r) {
      if (!inside[r]) continue;
      const uint pix = (ty * NF_TILE + ly0 + r) * pc.width + px;
      carry[pix] = T_after[r];
      [[unroll]] for (uint c = 0u; c < 5u; ++c) carry[(c + 1u) * plane + pix] = behind[r][c];
    }
  }
}
