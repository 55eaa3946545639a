#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, backward of pass 4: per tile, back to front over each pixel's contributors,
// the exact adjoint of compositing (engine/splat/rasterizer_ref.hpp, composite_adjoint). The
// pixels' gradients of each staged Gaussian are summed before they reach global memory:
//   shared:   contributing pixels add into shared-memory sums (float atomics on shared memory), one
//             global atomic per Gaussian and field per batch; only contributing lanes do work, which
//             matters where Gaussians are much smaller than a tile (fur) and on CPU devices;
//   subgroup: subgroup sums and one global atomic per subgroup (devices without shared float atomics).
//! variant shared -DNF_SHARED_SUMS
//! variant subgroup -DNF_SUBGROUP_SUMS
#extension GL_EXT_shader_atomic_float : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require

layout(constant_id = 0) const uint WG = 64;  // NF_TILE^2
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Proj { float proj[]; };
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

#ifdef NF_SHARED_SUMS
shared float s_grad[10][BATCH];  // per staged Gaussian: u, v, conic a b c, opacity, depth, ox, oy, conf
#else
void add(uint id, uint field, float value) {
  const float sum = subgroupAdd(value);
  if (subgroupElect() && sum != 0.0) atomicAdd(grad_proj[id * 12u + field], sum);
}
#endif

void main() {
  const uint tile = nf_linear_group();
  if (tile >= pc.tiles_x * ((pc.height + NF_TILE - 1u) / NF_TILE)) return;  // folded dispatches may overshoot
  const uint ty = tile / pc.tiles_x, tx = tile - ty * pc.tiles_x;
  const uint lx = gl_LocalInvocationID.x % NF_TILE, ly = gl_LocalInvocationID.x / NF_TILE;
  const uint px = tx * NF_TILE + lx, py = ty * NF_TILE + ly;
  const bool inside = px < pc.width && py < pc.height;
  const uint pix = inside ? py * pc.width + px : 0u;
  const uint plane = pc.width * pc.height;
  const float occluder = (inside && pc.has_body != 0u) ? body_depth[pix] : 3.0e38;
  const vec2 q = vec2(px, py) + 0.5;
  const uint start = ranges[2u * tile], end = ranges[2u * tile + 1u];
  const uint my_last = inside ? start + last[pix] : start;  // list positions < my_last contributed
  float g[5];
  for (uint c = 0u; c < 5u; ++c) g[c] = inside ? grad_image[c * plane + pix] : 0.0;
  float T_after = inside ? final_t[pix] : 1.0;
  float behind[5] = float[5](0.0, 0.0, 0.0, 0.0, 0.0);
  // Walk batches from the end of the list; every invocation runs the same loop (subgroup sums).
  const uint count = end - start;
  for (uint done_count = 0u; done_count < count; done_count += BATCH) {
    const uint n = min(BATCH, count - done_count);
    const uint first = end - done_count - n;  // this batch covers [first, first + n)
    barrier();
    if (gl_LocalInvocationID.x < n) nf_stage_gaussian(gl_LocalInvocationID.x, values[first + gl_LocalInvocationID.x]);
#ifdef NF_SHARED_SUMS
    for (uint f = 0u; f < 10u; ++f) s_grad[f][gl_LocalInvocationID.x] = 0.0;
#endif
    barrier();
    for (uint k = n; k-- > 0u;) {
      const uint position = first + k;
      float gu = 0.0, gv = 0.0, gca = 0.0, gcb = 0.0, gcc = 0.0, gop = 0.0, gox = 0.0, goy = 0.0, gconf = 0.0, gdepth = 0.0;
      bool contributes = inside && position < my_last && s_mean_opacity[k].w <= occluder;
      float power = 0.0, alpha = 0.0;
      if (contributes) {
        power = nf_power(k, q);
        alpha = nf_alpha(k, power);
        contributes = alpha > 0.0;
      }
      if (contributes) {
        const float one_minus = max(1e-6, 1.0 - alpha);
        const float Ti = T_after / one_minus;
        const float w = alpha * Ti;
        const vec3 attr = s_attr[k];
        const float f[5] = float[5](1.0, attr.x, attr.y, attr.z, s_mean_opacity[k].w);
        gox = g[1] * w;
        goy = g[2] * w;
        gconf = g[3] * w;
        gdepth = g[4] * w;
        float g_alpha = 0.0;
        for (uint c = 0u; c < 5u; ++c) g_alpha += g[c] * (Ti * f[c] - behind[c] / one_minus);
        for (uint c = 0u; c < 5u; ++c) behind[c] += w * f[c];
        T_after = Ti;
        if (s_mean_opacity[k].z * exp(power) < ALPHA_MAX) {  // the clamp passes no gradient
          const vec2 d = q - s_mean_opacity[k].xy;
          const vec3 c = s_conic[k];
          const float scale = 1.0 / (1.0 - ALPHA_MIN);
          const float g_power = g_alpha * scale * s_mean_opacity[k].z * exp(power);
          gop = g_alpha * scale * exp(power);
          gca = g_power * -0.5 * d.x * d.x;
          gcb = g_power * -d.x * d.y;
          gcc = g_power * -0.5 * d.y * d.y;
          gu = g_power * (c.x * d.x + c.y * d.y);
          gv = g_power * (c.y * d.x + c.z * d.y);
        }
      }
#ifdef NF_SHARED_SUMS
      if (contributes) {
        atomicAdd(s_grad[0][k], gu);
        atomicAdd(s_grad[1][k], gv);
        atomicAdd(s_grad[2][k], gca);
        atomicAdd(s_grad[3][k], gcb);
        atomicAdd(s_grad[4][k], gcc);
        atomicAdd(s_grad[5][k], gop);
        atomicAdd(s_grad[6][k], gdepth);
        atomicAdd(s_grad[7][k], gox);
        atomicAdd(s_grad[8][k], goy);
        atomicAdd(s_grad[9][k], gconf);
      }
#else
      // Every invocation of the subgroup reaches here for the same k: sum, then one atomic each.
      if (subgroupAny(contributes)) {
        const uint id = s_id[k];
        add(id, 0u, gu);
        add(id, 1u, gv);
        add(id, 2u, gca);
        add(id, 3u, gcb);
        add(id, 4u, gcc);
        add(id, 5u, gop);
        add(id, 6u, gdepth);
        add(id, 7u, gox);
        add(id, 8u, goy);
        add(id, 9u, gconf);
      }
#endif
    }
#ifdef NF_SHARED_SUMS
    barrier();
    if (gl_LocalInvocationID.x < n) {
      const uint id = s_id[gl_LocalInvocationID.x];
      for (uint f = 0u; f < 10u; ++f) {
        const float v = s_grad[f][gl_LocalInvocationID.x];
        if (v != 0.0) atomicAdd(grad_proj[id * 12u + f], v);
      }
    }
#endif
  }
}
