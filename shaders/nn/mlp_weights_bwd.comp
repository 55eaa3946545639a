#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// Parameter gradients of one layer, without atomics: dW[o][k] = sum_s dz[s][o] x[s][k] and
// db[o] = sum_s dz[s][o], summed over one slab of samples into that slab's partial copy;
// mlp_reduce_partials then adds the copies.
//
// A workgroup owns WG outputs (one per lane) x a block of COLS inputs x one slab. It first stages
// the block's inputs for the slab's samples in shared memory; after the barrier every input is
// read at a constant offset outside any loop or branch, the one load lavapipe (Mesa 22.3) turns
// into a single broadcast without a bounds check (see mlp_fwd.comp). Each lane then fetches
// its output's dz for four samples at a time from the transposed copy dz^T (written by the
// activation adjoint for the top layer, by the input adjoint above for hidden ones; one texel
// fetch, a straight-line gather, per 128 multiply-adds) and keeps COLS sums in registers. The slab is
// unrolled; without branches LLVM compiles it in about a second. Workgroups take the outputs and
// input blocks of one slab in turn, so the slab's rows are read from cache after the first.
layout(constant_id = 0) const uint WG = 64;      // outputs per workgroup
layout(constant_id = 1) const uint SLAB4 = 64;   // samples per slab / 4
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_rows.glsl"

const uint COLS = 32u;  // inputs per block: accumulators per lane
const uint SLAB = SLAB4 * 4u;

layout(std430, binding = 0) writeonly buffer Partials { vec4 partials[]; };  // [slab][slab_stride4]
layout(binding = 16) uniform samplerBuffer dzt;  // [out][dzt_stride4]: dz transposed, samples contiguous
layout(binding = 17) uniform samplerBuffer x;    // [batch][in4]: nf_rows.glsl

layout(push_constant) uniform Push {
  uint batch;
  uint in4;
  uint out_dim;
  uint dzt_stride4;   // vec4 per row of dz^T (whole slabs)
  uint o_groups;      // workgroup g: outputs g % o_groups, input block (g / o_groups) % i_blocks,
  uint i_blocks;      // slab g / (o_groups * i_blocks)
  uint groups;        // o_groups * i_blocks * slabs
  uint x_interleaved;  // nf_rows.glsl layout of x
} pc;

shared vec4 xs[COLS / 4u * SLAB];  // xs[c4 * SLAB + s]: inputs 4 c4 .. +3 of the block, slab sample s

void main() {
  // A folded dispatch rounds its groups up: the extra ones compute on the last group's data and
  // store nothing (no early return: lavapipe treats all code after one as inside control flow).
  const bool live = nf_linear_group() < pc.groups;
  const uint group = min(nf_linear_group(), pc.groups - 1u);
  const uint og = group % pc.o_groups, ib = (group / pc.o_groups) % pc.i_blocks;
  const uint slab = group / (pc.o_groups * pc.i_blocks);
  const uint first = slab * SLAB, k4_first = ib * (COLS / 4u);

  // Samples past the batch and inputs past the row stage clamped copies: their dz is selected away
  // below, and their sums are not stored.
  for (uint t = gl_LocalInvocationID.x; t < COLS / 4u * SLAB; t += WG) {
    const uint c4 = t % (COLS / 4u), s = t / (COLS / 4u);
    const uint at = min(first + s, pc.batch - 1u), k4 = min(k4_first + c4, pc.in4 - 1u);
    xs[c4 * SLAB + s] = texelFetch(x, int(nf_row_index(at, k4, pc.in4, pc.x_interleaved != 0u)));
  }
  barrier();

  const uint o = og * WG + gl_LocalInvocationID.x;
  const uint row = min(o, pc.out_dim - 1u) * pc.dzt_stride4 + slab * SLAB4;
  float acc[COLS];
  [[unroll]] for (uint c = 0u; c < COLS; ++c) acc[c] = 0.0;
  float bias = 0.0;
  [[unroll]] for (uint j = 0u; j < SLAB4; ++j) {
    // dz^T past the batch holds whatever was there: select it away (a product with zero keeps NaN).
    const bvec4 real = lessThan(uvec4(first + 4u * j) + uvec4(0u, 1u, 2u, 3u), uvec4(pc.batch));
    const vec4 d = mix(vec4(0.0), texelFetch(dzt, int(row + j)), real);
    [[unroll]] for (uint c4 = 0u; c4 < COLS / 4u; ++c4) {
      const vec4 x0 = xs[c4 * SLAB + 4u * j], x1 = xs[c4 * SLAB + 4u * j + 1u];
      const vec4 x2 = xs[c4 * SLAB + 4u * j + 2u], x3 = xs[c4 * SLAB + 4u * j + 3u];
      [[unroll]] for (uint e = 0u; e < 4u; ++e)
        acc[4u * c4 + e] = fma(d.x, x0[e], fma(d.y, x1[e], fma(d.z, x2[e], fma(d.w, x3[e], acc[4u * c4 + e]))));
    }
    bias += (d.x + d.y) + (d.z + d.w);
  }

  // Slab copies are whole vec4 apart: weights [out][in4] vec4, then the biases.
  const bool store = live && o < pc.out_dim;
  const uint weights4 = pc.out_dim * pc.in4;
  const uint slab_base = slab * (weights4 + (pc.out_dim + 3u) / 4u);
  [[unroll]] for (uint c4 = 0u; c4 < COLS / 4u; ++c4) {
    const uint k4 = k4_first + c4;
    if (store && k4 < pc.in4)
      partials[slab_base + o * pc.in4 + k4] = vec4(acc[4u * c4], acc[4u * c4 + 1u], acc[4u * c4 + 2u], acc[4u * c4 + 3u]);
  }
  if (store && ib == 0u) partials[slab_base + weights4 + o / 4u][o % 4u] = bias;
}
