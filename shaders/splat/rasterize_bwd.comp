#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, backward of pass 4: per tile, back to front over each pixel's contributors,
// the exact adjoint of compositing (engine/splat/rasterizer_ref.hpp, composite_adjoint). Gaussians
// reach pixels as in the forward (nf_splat_composite.glsl), batch by batch from the end of the
// list. A Gaussian's gradient is summed over its subgroup's pixels with subgroup sums (kept by the
// lane that loaded it), then over the tile's subgroups:
//   shared:   into shared memory with float atomics, then one global atomic per Gaussian and field;
//   subgroup: one global atomic per subgroup, Gaussian and field (devices without shared float
//             atomics).
//! variant shared -DNF_SHARED_SUMS
//! variant subgroup -DNF_SUBGROUP_SUMS
#extension GL_EXT_shader_atomic_float : require

layout(constant_id = 0) const uint WG = 64;  // NF_TILE^2
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Proj { vec4 proj4[]; };  // 3 per Gaussian
layout(std430, binding = 1) readonly buffer Values { uint values[]; };
layout(std430, binding = 2) readonly buffer Ranges { uint ranges[]; };
layout(std430, binding = 3) readonly buffer Body { float body_depth[]; };
layout(std430, binding = 4) readonly buffer FinalT { float final_t[]; };
layout(std430, binding = 5) readonly buffer Last { uint last[]; };
layout(std430, binding = 6) readonly buffer GradImage { float grad_image[]; };  // 5 planes
layout(std430, binding = 7) buffer GradProj { float grad_proj[]; };             // per Gaussian * 12, accumulated

layout(push_constant) uniform Push {
  uint width, height, tiles_x, has_body;
} pc;

#include "nf_splat_composite.glsl"

const uint FIELDS = 10u;  // u, v, conic a b c, opacity, depth, orientation x, y, confidence (proj order)

#ifdef NF_SHARED_SUMS
shared float s_grad[FIELDS][WG];  // per batch slot (a batch is at most one subgroup <= WG)
#endif
shared uint s_used;  // how far into the list any pixel of the tile went

// Per-pixel adjoint state.
float g[5];           // dL/d(alpha, orientation x, y, confidence, depth) of this pixel
float T_after;        // transmittance behind the Gaussian being undone
float behind[5];      // what the Gaussians behind it added to each channel
float occluder;
vec2 q;
bool inside;
uint my_last;

// This pixel's gradient of the Gaussian at list position `position` (zero when it did not
// contribute), and the step back over it.
void undo(const NfGaussian gs, uint position, out float grad[FIELDS], out bool contributes) {
  for (uint f = 0u; f < FIELDS; ++f) grad[f] = 0.0;
  contributes = inside && position < my_last && gs.depth <= occluder;
  float power = 0.0, alpha = 0.0;
  if (contributes) {
    power = nf_power_of(gs, q);
    alpha = nf_alpha_of(gs, power);
    contributes = alpha > 0.0;
  }
  if (!contributes) return;
  const float one_minus = max(1e-6, 1.0 - alpha);
  const float Ti = T_after / one_minus;
  const float w = alpha * Ti;
  const float f5[5] = float[5](1.0, gs.attr.x, gs.attr.y, gs.attr.z, gs.depth);
  grad[7] = g[1] * w;
  grad[8] = g[2] * w;
  grad[9] = g[3] * w;
  grad[6] = g[4] * w;
  float g_alpha = 0.0;
  for (uint c = 0u; c < 5u; ++c) g_alpha += g[c] * (Ti * f5[c] - behind[c] / one_minus);
  for (uint c = 0u; c < 5u; ++c) behind[c] += w * f5[c];
  T_after = Ti;
  const float e = exp(power);
  if (gs.opacity * e < ALPHA_MAX) {  // the clamp passes no gradient
    const vec2 d = q - gs.mean;
    const vec3 c = gs.conic;
    const float scale = 1.0 / (1.0 - ALPHA_MIN);
    const float g_power = g_alpha * scale * gs.opacity * e;
    grad[5] = g_alpha * scale * e;
    grad[2] = g_power * -0.5 * d.x * d.x;
    grad[3] = g_power * -d.x * d.y;
    grad[4] = g_power * -0.5 * d.y * d.y;
    grad[0] = g_power * (c.x * d.x + c.y * d.y);
    grad[1] = g_power * (c.y * d.x + c.z * d.y);
  }
}

void main() {
  const uint tile = nf_linear_group();
  if (tile >= pc.tiles_x * ((pc.height + NF_TILE - 1u) / NF_TILE)) return;  // folded dispatches may overshoot
  const uint ty = tile / pc.tiles_x, tx = tile - ty * pc.tiles_x;
  const uint lx = gl_LocalInvocationID.x % NF_TILE, ly = gl_LocalInvocationID.x / NF_TILE;
  const uint px = tx * NF_TILE + lx, py = ty * NF_TILE + ly;
  inside = px < pc.width && py < pc.height;
  const uint pix = inside ? py * pc.width + px : 0u;
  const uint plane = pc.width * pc.height;
  occluder = (inside && pc.has_body != 0u) ? body_depth[pix] : 3.0e38;
  q = vec2(px, py) + 0.5;
  vec2 lo, hi;
  nf_subgroup_rect(q, lo, hi);
  const uint start = ranges[2u * tile];
  my_last = inside ? start + last[pix] : start;  // list positions < my_last contributed
  for (uint c = 0u; c < 5u; ++c) {
    g[c] = inside ? grad_image[c * plane + pix] : 0.0;
    behind[c] = 0.0;
  }
  T_after = inside ? final_t[pix] : 1.0;
  const uint lane = gl_SubgroupInvocationID;
  if (gl_LocalInvocationIndex == 0u) s_used = 0u;
#ifdef NF_SHARED_SUMS
  for (uint i = gl_LocalInvocationIndex; i < FIELDS * WG; i += WG) s_grad[i / WG][i % WG] = 0.0;
#endif
  barrier();
  // Where the forward stopped (every pixel opaque) nothing behind contributed: start there. In
  // dense fur most of a tile's list lies behind it.
  const uint subgroup_last = subgroupMax(my_last);
  if (subgroupElect()) atomicMax(s_used, subgroup_last - start);
  barrier();
  // Batches from the end of the used list, the same for every subgroup (the shared sums rely on it).
  const uint count = s_used;
  const uint end_used = start + count;
  for (uint done_count = 0u; done_count < count; done_count += gl_SubgroupSize) {
    const uint n = min(gl_SubgroupSize, count - done_count);
    const uint first = end_used - done_count - n;  // this batch covers [first, first + n)
    const uint my_id = values[first + min(lane, n - 1u)];
    const NfGaussianLanes mine = nf_load_gaussian(my_id);
    const uvec4 reach = subgroupBallot(lane < n && first + lane < subgroup_last && nf_reaches(nf_unpack(mine), lo, hi));
    float sums[FIELDS];  // lane j: this subgroup's gradient of the batch's Gaussian j
    for (uint f = 0u; f < FIELDS; ++f) sums[f] = 0.0;
    for (uint word = (n + 31u) / 32u; word-- > 0u;) {
      uint bits = reach[word];
      while (bits != 0u) {  // back to front: highest list position first
        const uint bit = uint(findMSB(bits));
        bits &= ~(1u << bit);
        const uint j = word * 32u + bit;
        float grad[FIELDS];
        bool contributes;
        undo(nf_broadcast(mine, j), first + j, grad, contributes);
        if (subgroupAny(contributes)) {
          for (uint f = 0u; f < FIELDS; ++f) {
            const float s = subgroupAdd(grad[f]);
            if (lane == j) sums[f] = s;
          }
        }
      }
    }
#ifdef NF_SHARED_SUMS
    if (lane < n)
      for (uint f = 0u; f < FIELDS; ++f)
        if (sums[f] != 0.0) atomicAdd(s_grad[f][lane], sums[f]);
    barrier();
    if (gl_LocalInvocationIndex < n) {
      const uint slot = gl_LocalInvocationIndex, id = values[first + slot];
      for (uint f = 0u; f < FIELDS; ++f) {
        const float v = s_grad[f][slot];
        if (v != 0.0) atomicAdd(grad_proj[id * 12u + f], v);
        s_grad[f][slot] = 0.0;
      }
    }
    barrier();
#else
    if (lane < n)
      for (uint f = 0u; f < FIELDS; ++f)
        if (sums[f] != 0.0) atomicAdd(grad_proj[my_id * 12u + f], sums[f]);
#endif
  }
}
