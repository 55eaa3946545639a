#version 460
#extension GL_GOOGLE_include_directive : require
// Parameter gradients of one layer, without atomics: each workgroup sums dW[o][k] = sum_s dz[o][s]
// x[k][s] (and db[o] = sum_s dz[o][s], as input column k = in_dim of constant 1) over its slab of
// samples into its own partial copy; mlp_reduce_partials then adds the copies. Lanes run over
// samples (vector loads); each invocation loops over SLAB_ITEMS samples before one subgroup sum.

layout(constant_id = 0) const uint WG = 64;
layout(constant_id = 1) const uint SLAB_ITEMS = 32;
layout(local_size_x_id = 0) in;
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer GradZ { float dz[]; };  // out_dim x batch
layout(std430, binding = 1) readonly buffer Input { float x[]; };   // in_dim x batch
layout(std430, binding = 2) writeonly buffer Partials { float partials[]; };  // slabs x (out*in + out)

layout(push_constant) uniform Push {
  uint batch;
  uint in_dim;
  uint out_dim;
  uint blocks_per_group;  // 4x4 (o, k) blocks handled by one workgroup
} pc;

const uint B = 4u;  // block edge
shared float block_sums[WG][B * B];  // one row per subgroup (WG bounds the subgroup count)

void main() {
  const uint slab = gl_WorkGroupID.x;
  const uint layer_params = pc.out_dim * pc.in_dim + pc.out_dim;
  const uint k_blocks = (pc.in_dim + 1u + B - 1u) / B;  // + the bias column
  const uint total_blocks = ((pc.out_dim + B - 1u) / B) * k_blocks;
  const uint first_block = gl_WorkGroupID.y * pc.blocks_per_group;
  const uint slab_base = slab * WG * SLAB_ITEMS + gl_LocalInvocationID.x;
  for (uint blk = first_block; blk < min(first_block + pc.blocks_per_group, total_blocks); ++blk) {
    const uint o0 = (blk / k_blocks) * B, k0 = (blk % k_blocks) * B;
    float acc[B][B];
    for (uint a = 0u; a < B; ++a)
      for (uint b = 0u; b < B; ++b) acc[a][b] = 0.0;
    for (uint j = 0u; j < SLAB_ITEMS; ++j) {
      const uint s = slab_base + j * WG;
      if (s >= pc.batch) break;
      float g[B], xv[B];
      for (uint a = 0u; a < B; ++a) g[a] = dz[min(o0 + a, pc.out_dim - 1u) * pc.batch + s];
      for (uint b = 0u; b < B; ++b) {
        const uint k = k0 + b;
        xv[b] = k < pc.in_dim ? x[k * pc.batch + s] : (k == pc.in_dim ? 1.0 : 0.0);
      }
      for (uint a = 0u; a < B; ++a)
        for (uint b = 0u; b < B; ++b) acc[a][b] = fma(g[a], xv[b], acc[a][b]);
    }
    for (uint a = 0u; a < B; ++a)
      for (uint b = 0u; b < B; ++b) {
        const float sum = subgroupAdd(acc[a][b]);
        if (subgroupElect()) block_sums[gl_SubgroupID][a * B + b] = sum;
      }
    barrier();
    const uint e = gl_LocalInvocationIndex;
    if (e < B * B) {
      float total = 0.0;
      for (uint sg = 0u; sg < gl_NumSubgroups; ++sg) total += block_sums[sg][e];
      const uint o = o0 + e / B, k = k0 + e % B;
      if (o < pc.out_dim && k <= pc.in_dim) {
        const uint p = k < pc.in_dim ? o * pc.in_dim + k : pc.out_dim * pc.in_dim + o;
        partials[slab * layer_params + p] = total;
      }
    }
    barrier();
  }
}
