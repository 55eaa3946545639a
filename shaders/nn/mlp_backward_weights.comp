#version 460
#extension GL_GOOGLE_include_directive : require
// Parameter gradients of one layer, without atomics: each workgroup sums dW[o][k] = sum_s dz[s][o]
// x[s][k] (and db[o] = sum_s dz[s][o], as the input column k = in_stride of constant 1) over its
// slab of samples into its own partial copy; mlp_reduce_partials then adds the copies. Lanes run
// over samples; each invocation loops over SLAB_ITEMS samples for a 4x4 block of (o, k) before one
// subgroup sum per entry.

layout(constant_id = 0) const uint WG = 64;
layout(constant_id = 1) const uint SLAB_ITEMS = 32;
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

shared vec4 block_sums[WG][4];  // one row per subgroup (WG bounds the subgroup count)

void main() {
  const uint slab = gl_WorkGroupID.x;
  const uint in_stride = pc.in4 * 4u;
  const uint layer_params = pc.out_dim * in_stride + pc.out_dim;
  const uint k_blocks = pc.in4 + 1u;  // + the bias column
  const uint total_blocks = pc.out4 * k_blocks;
  const uint first_block = gl_WorkGroupID.y * pc.blocks_per_group;
  const uint slab_base = slab * WG * SLAB_ITEMS + gl_LocalInvocationID.x;
  for (uint blk = first_block; blk < min(first_block + pc.blocks_per_group, total_blocks); ++blk) {
    const uint o4 = blk / k_blocks, k4 = blk % k_blocks;
    vec4 acc[4] = vec4[4](vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0));  // acc[j][i]: o = 4 o4 + j, k = 4 k4 + i
    for (uint t = 0u; t < SLAB_ITEMS; ++t) {
      const uint s = slab_base + t * WG;
      if (s >= pc.batch) break;
      const vec4 g = dz[s * pc.out4 + o4];
      const vec4 xv = k4 < pc.in4 ? x[s * pc.in4 + k4] : vec4(1.0, 0.0, 0.0, 0.0);
      for (uint j = 0u; j < 4u; ++j) acc[j] = fma(vec4(g[j]), xv, acc[j]);
    }
    for (uint j = 0u; j < 4u; ++j) {
      const vec4 sum = subgroupAdd(acc[j]);
      if (subgroupElect()) block_sums[gl_SubgroupID][j] = sum;
    }
    barrier();
    const uint e = gl_LocalInvocationIndex;
    if (e < 16u) {
      const uint j = e / 4u, i = e % 4u;
      float total = 0.0;
      for (uint sg = 0u; sg < gl_NumSubgroups; ++sg) total += block_sums[sg][j][i];
      const uint o = 4u * o4 + j;
      if (o < pc.out_dim) {
        if (k4 < pc.in4) partials[slab * layer_params + o * in_stride + 4u * k4 + i] = total;
        else if (i == 0u) partials[slab * layer_params + pc.out_dim * in_stride + o] = total;
      }
    }
    barrier();
  }
}
