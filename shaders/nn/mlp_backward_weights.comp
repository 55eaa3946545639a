#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// Parameter gradients of one layer, without atomics: dW[o][k] = sum_s dz[s][o] x[s][k] and
// db[o] = sum_s dz[s][o] (the input column k = in_stride of constant 1), summed over one slab of
// samples into that slab's partial copy; mlp_reduce_partials then adds the copies.
//
// Each invocation owns 4 outputs x 4 KV inputs of one slab and walks its samples, fetching the
// sample's 4 dz and 4 KV inputs and adding their outer product. Neighbouring lanes own neighbouring
// outputs of the same inputs, so their dz fetches share cache lines and their input fetches hit the
// same address; blocks run slab-major, so a slab's rows stay in cache while its blocks are summed.
// Why fetches and not loads: on lavapipe (Mesa 22.3) a load inside a loop is per lane, and a texel
// fetch is a straight-line gather where a storage-buffer load is a loop over the lanes with bounds
// checks, and a subgroup broadcast first searches the execution mask lane by lane (~40
// instructions per value). 16 KV accumulators stay in registers.
layout(constant_id = 0) const uint WG = 64;
layout(constant_id = 1) const uint SLAB = 512;  // samples per slab (a multiple of UNROLL)
layout(constant_id = 2) const uint KV = 2;      // input vec4 per block
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_rows.glsl"

const uint UNROLL = 8u;  // samples per loop trip: a trip costs a mask update per accumulator

layout(std430, binding = 0) writeonly buffer Partials { float partials[]; };  // [slab][out*in_stride + out]
layout(binding = 16) uniform samplerBuffer dz;  // [batch][out4]: nf_rows.glsl
layout(binding = 17) uniform samplerBuffer x;   // [batch][in4]: nf_rows.glsl

layout(push_constant) uniform Push {
  uint batch;
  uint in4;
  uint out4;
  uint out_dim;
  uint k_blocks;  // ceil((in4 + 1) / KV)
  uint blocks;    // slabs * k_blocks * out4
  uint dz_interleaved;  // nf_rows.glsl layouts
  uint x_interleaved;
} pc;

void main() {
  const uint block = nf_linear_index();
  if (block >= pc.blocks) return;
  const uint o4 = block % pc.out4, kb = (block / pc.out4) % pc.k_blocks;
  const uint slab = block / (pc.out4 * pc.k_blocks);
  const uint k0 = kb * KV;  // first input vec4 (in4: the bias column)
  const uint first = slab * SLAB, last = min(first + SLAB, pc.batch);

  vec4 acc[4u * KV];  // acc[4 v + c]: outputs 4 o4 .. +3 against input 4 (k0 + v) + c
  [[unroll]] for (uint e = 0u; e < 4u * KV; ++e) acc[e] = vec4(0.0);
  // do-while: on lavapipe a for loop runs one more masked body before it leaves. Samples past the
  // batch read the last one's dz and count zero inputs.
  uint base = first;
  do {
    [[unroll]] for (uint u = 0u; u < UNROLL; ++u) {
      const uint s = base + u, s_read = min(s, pc.batch - 1u);
      const vec4 a = texelFetch(dz, int(nf_row_index(s_read, o4, pc.out4, pc.dz_interleaved != 0u)));
      [[unroll]] for (uint v = 0u; v < KV; ++v) {
        const uint k4 = k0 + v;
        const vec4 fetched = texelFetch(x, int(nf_row_index(s_read, min(k4, pc.in4 - 1u), pc.in4, pc.x_interleaved != 0u)));
        vec4 b = k4 < pc.in4 ? fetched : k4 == pc.in4 ? vec4(1.0, 0.0, 0.0, 0.0) : vec4(0.0);
        b = s < last ? b : vec4(0.0);
        [[unroll]] for (uint c = 0u; c < 4u; ++c) acc[4u * v + c] = fma(a, vec4(b[c]), acc[4u * v + c]);
      }
    }
  } while ((base += UNROLL) < last);

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
