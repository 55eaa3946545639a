#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_shuffle : require
// Parameter gradients of one layer, without atomics: dW[o][k] = sum_s dz[s][o] x[s][k] and
// db[o] = sum_s dz[s][o] (the input column k = in_stride of constant 1), summed over one slab of
// samples into that slab's partial copy; mlp_reduce_partials then adds the copies.
//
// A team of TEAM lanes owns 4 TEAM outputs (4 per lane) x 4 KV inputs for one slab. Per group of
// TEAM samples each lane fetches the inputs of one sample (its own), then for each sample j of the
// group it fetches its own 4 outputs' dz and takes sample j's inputs from lane j. Why this shape:
// on lavapipe (Mesa 22.3) every load inside a loop is per lane, and the cheapest per-lane load is a
// texel fetch (a straight-line gather; a storage-buffer load is a loop over the lanes with bounds
// checks), while a broadcast from a constant lane is one register shuffle. So every fetched value
// is distinct and useful, and the shared operand travels by broadcast. 4 x 4 KV accumulators stay
// in registers. Teams run slab-major, so one slab's rows stay in cache while its blocks are summed.
// On devices whose subgroup is wider than the team, lanes reach their team by subgroupShuffle.
//! variant t1 -DTEAM=1
//! variant t2 -DTEAM=2
//! variant t4 -DTEAM=4
//! variant t8 -DTEAM=8

layout(constant_id = 0) const uint WG = 64;
layout(constant_id = 1) const uint SLAB = 512;            // samples per slab (a multiple of TEAM)
layout(constant_id = 2) const uint KV = 2;                // input vec4 per block
layout(constant_id = 3) const bool TEAM_IS_SUBGROUP = true;  // else teams reach each other by shuffle
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) writeonly buffer Partials { float partials[]; };  // [slab][out*in_stride + out]
layout(binding = 16) uniform samplerBuffer dz;  // [batch][out4]
layout(binding = 17) uniform samplerBuffer x;   // [batch][in4]

layout(push_constant) uniform Push {
  uint batch;
  uint in4;
  uint out4;
  uint out_dim;
  uint o_blocks;  // ceil(out4 / TEAM)
  uint k_blocks;  // ceil((in4 + 1) / KV)
  uint teams;     // slabs * k_blocks * o_blocks
} pc;

float from_lane(float v, uint j) {
  if (TEAM == 1) return v;
  if (TEAM_IS_SUBGROUP) return subgroupBroadcast(v, j);
  return subgroupShuffle(v, (gl_SubgroupInvocationID & ~(TEAM - 1u)) + j);
}

void main() {
  const uint lane = gl_SubgroupInvocationID & (TEAM - 1u);
  const uint team = min(nf_linear_index() / TEAM, pc.teams - 1u);  // tail teams repeat the last
  const uint ob = team % pc.o_blocks, kb = (team / pc.o_blocks) % pc.k_blocks;
  const uint slab = team / (pc.o_blocks * pc.k_blocks);
  const uint o4 = ob * TEAM + lane;  // this lane's outputs: 4 o4 .. 4 o4 + 3
  const uint k0 = kb * KV;           // first input vec4 (in4: the bias column)
  const uint first = slab * SLAB, last = min(first + SLAB, pc.batch);
  const uint o4_read = min(o4, pc.out4 - 1u);

  vec4 acc[4u * KV];  // acc[4 v + c]: outputs 4 o4 .. +3 against input 4 (k0 + v) + c
  [[unroll]] for (uint e = 0u; e < 4u * KV; ++e) acc[e] = vec4(0.0);

  // do-while: on lavapipe a for loop runs one more masked body before it leaves.
  uint base = first;
  do {
    const uint s_own = base + lane;
    vec4 b[KV];  // this lane's sample's inputs (zero past the batch)
    [[unroll]] for (uint v = 0u; v < KV; ++v) {
      const uint k4 = k0 + v;
      const vec4 fetched = texelFetch(x, int(min(s_own, pc.batch - 1u) * pc.in4 + min(k4, pc.in4 - 1u)));
      const vec4 value = k4 < pc.in4 ? fetched : k4 == pc.in4 ? vec4(1.0, 0.0, 0.0, 0.0) : vec4(0.0);
      b[v] = s_own < last ? value : vec4(0.0);
    }
#define NF_STEP(j)                                                                           \
    {                                                                                        \
      const vec4 a = texelFetch(dz, int(min(base + (j), pc.batch - 1u) * pc.out4 + o4_read)); \
      [[unroll]] for (uint v = 0u; v < KV; ++v)                                              \
        [[unroll]] for (uint c = 0u; c < 4u; ++c)                                            \
          acc[4u * v + c] = fma(a, vec4(from_lane(b[v][c], (j))), acc[4u * v + c]);          \
    }
    NF_STEP(0u)
#if TEAM > 1
    NF_STEP(1u)
#endif
#if TEAM > 2
    NF_STEP(2u) NF_STEP(3u)
#endif
#if TEAM > 4
    NF_STEP(4u) NF_STEP(5u) NF_STEP(6u) NF_STEP(7u)
#endif
#undef NF_STEP
  } while ((base += TEAM) < last);

  if (nf_linear_index() / TEAM >= pc.teams || o4 >= pc.out4) return;
  const uint in_stride = pc.in4 * 4u;
  const uint slab_base = slab * (pc.out_dim * in_stride + pc.out_dim);
  [[unroll]] for (uint v = 0u; v < KV; ++v) {
    const uint k4 = k0 + v;
    [[unroll]] for (uint i = 0u; i < 4u; ++i) {
      const uint o = 4u * o4 + i;
      if (o >= pc.out_dim) continue;
      if (k4 < pc.in4) {
        [[unroll]] for (uint c = 0u; c < 4u; ++c) partials[slab_base + o * in_stride + 4u * k4 + c] = acc[4u * v + c][i];
      } else if (k4 == pc.in4) {
        partials[slab_base + pc.out_dim * in_stride + o] = acc[4u * v][i];
      }
    }
  }
}
