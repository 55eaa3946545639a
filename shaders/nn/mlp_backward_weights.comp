#version 460
#extension GL_GOOGLE_include_directive : require
// Parameter gradients of one layer, without atomics: each workgroup sums dW[o][k] = sum_s dz[s][o]
// x[s][k] (and db[o] = sum_s dz[s][o], as the input column k = in_stride of constant 1) over its
// slab of samples into its own partial copy; mlp_reduce_partials then adds the copies. Lanes run
// over samples; each invocation loops over SLAB_ITEMS samples for a block of 4 BO outputs x 4 BK
// inputs before one subgroup sum per entry. Per-lane loads (gathers on CPU devices) dominate, so
// the block is as large as registers allow: BO + BK vec4 loads feed 16 BO BK multiply-adds.

layout(constant_id = 0) const uint WG = 64;
layout(constant_id = 1) const uint SLAB_ITEMS = 32;
layout(constant_id = 2) const uint BO = 2;  // output vec4 per block
layout(constant_id = 3) const uint BK = 2;  // input vec4 per block (the bias column counts as one)
layout(local_size_x_id = 0) in;
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer GradZ { vec4 dz[]; };  // [batch][out4]
layout(std430, binding = 1) readonly buffer Input { vec4 x[]; };   // [batch][in4]
layout(std430, binding = 2) writeonly buffer Partials { float partials[]; };  // [slab][out*in_stride + out]

layout(push_constant) uniform Push {
  uint batch;
  uint in4;
  uint out4;
  uint out_dim;
  uint blocks_per_group;
} pc;

shared vec4 block_sums[WG][4u * BO * BK];  // one row per subgroup (WG bounds the subgroup count)

void main() {
  const uint slab = gl_WorkGroupID.x;
  const uint in_stride = pc.in4 * 4u;
  const uint layer_params = pc.out_dim * in_stride + pc.out_dim;
  const uint k_vec = pc.in4 + 1u;  // + the bias column
  const uint o_blocks = (pc.out4 + BO - 1u) / BO, k_blocks = (k_vec + BK - 1u) / BK;
  const uint total_blocks = o_blocks * k_blocks;
  const uint first_block = gl_WorkGroupID.y * pc.blocks_per_group;
  const uint slab_base = slab * WG * SLAB_ITEMS + gl_LocalInvocationID.x;
  // Loops are do-while: on lavapipe a for loop runs one more masked body before it leaves, and
  // these run once or a few times.
  const uint last_block = min(first_block + pc.blocks_per_group, total_blocks);
  uint blk = first_block;
  if (blk < last_block) do {
    const uint o0 = (blk / k_blocks) * BO, k0 = (blk % k_blocks) * BK;
    vec4 acc[4u * BO * BK];  // acc[(a * 4 + j) * BK + b]: o = 4 (o0 + a) + j, k = 4 (k0 + b) + i
    for (uint e = 0u; e < 4u * BO * BK; ++e) acc[e] = vec4(0.0);
    uint t = 0u;
    do {
      const uint s = slab_base + t * WG;
      if (s >= pc.batch) break;
      vec4 g[BO], xv[BK];
      for (uint a = 0u; a < BO; ++a) g[a] = o0 + a < pc.out4 ? dz[s * pc.out4 + o0 + a] : vec4(0.0);
      for (uint b = 0u; b < BK; ++b) {
        const uint k4 = k0 + b;
        xv[b] = k4 < pc.in4 ? x[s * pc.in4 + k4] : k4 == pc.in4 ? vec4(1.0, 0.0, 0.0, 0.0) : vec4(0.0);
      }
      for (uint a = 0u; a < BO; ++a)
        for (uint j = 0u; j < 4u; ++j)
          for (uint b = 0u; b < BK; ++b) acc[(a * 4u + j) * BK + b] = fma(vec4(g[a][j]), xv[b], acc[(a * 4u + j) * BK + b]);
    } while (++t < SLAB_ITEMS);
    for (uint e = 0u; e < 4u * BO * BK; ++e) {
      const vec4 sum = subgroupAdd(acc[e]);
      if (subgroupElect()) block_sums[gl_SubgroupID][e] = sum;
    }
    barrier();
    uint e = gl_LocalInvocationIndex;
    if (e < 16u * BO * BK) do {
      const uint row = e / 4u, i = e % 4u;  // row = (a * 4 + j) * BK + b
      const uint b = row % BK, aj = row / BK, a = aj / 4u, j = aj % 4u;
      float total = 0.0;
      for (uint sg = 0u; sg < gl_NumSubgroups; ++sg) total += block_sums[sg][row][i];
      const uint o = 4u * (o0 + a) + j, k4 = k0 + b;
      if (o < pc.out_dim && k4 <= pc.in4) {
        if (k4 < pc.in4) partials[slab * layer_params + o * in_stride + 4u * k4 + i] = total;
        else if (i == 0u) partials[slab * layer_params + pc.out_dim * in_stride + o] = total;
      }
    } while ((e += WG) < 16u * BO * BK);
    barrier();
  } while (++blk < last_block);
}
