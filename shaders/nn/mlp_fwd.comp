#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// One MLP layer, y = act(W x + b), for a block of COLS output rows and WG x SAMPLES samples per
// workgroup, reading IN4 input vec4 (a chunk of the layer's inputs) per dispatch; COLS x SAMPLES
// outputs stay in registers. One dispatch covers every row block of the layer: workgroups take the
// row blocks of one sample tile in turn, so a tile's inputs are read from memory once and from
// cache by the other blocks.
//
// The workgroup first stages its block of weights in shared memory. After the barrier every
// weight is read at a constant offset, outside any loop or branch: that is the one load lavapipe
// (Mesa 22.3) turns into a single broadcast, with no bounds check (a uniform-buffer load pays a
// compare and a branch per component; anywhere inside control flow, every lane loads on its own).
// Without those branches LLVM compiles a whole 256-input layer (8192 multiply-adds per lane) in
// about a second. GPUs read broadcast shared values at full rate too. Inputs come by texel fetch,
// a straight-line gather, where a storage-buffer load loops over the lanes. The tail lanes are
// clamped instead of returning (a barrier needs every invocation), and only the stores are
// conditional. Later chunks of a wider layer add to y; the bias enters with the first chunk, the
// activation with the last (a specialisation constant: lavapipe evaluates both sides of a branch).
// The same kernel computes the input adjoint dx = W^T dz, on transposed weights. There, for a
// hidden layer below, the last chunk also applies that layer's activation derivative (ADJOINT:
// from its output, or its pre-activation for Sine, by texel fetch) and writes the result twice:
// as that layer's dz in y's layout and transposed ([row][zt_stride], samples contiguous) for its
// weight gradient, which saves a pass that would read and write all of it again.
// Layout: engine/nn/mlp_config.hpp. Host: engine/nn/mlp.cpp.
//! variant c32s1 -DCOLS=32 -DSAMPLES=1

layout(constant_id = 0) const uint WG = 256;
layout(constant_id = 3) const uint IN4 = 1;         // input vec4 in this dispatch's chunk
layout(constant_id = 4) const uint ACTIVATION = 0;  // NF_ACT_*: NONE but on a layer's last chunk
layout(constant_id = 5) const bool STORE_Z = false;  // keep pre-activations (Sine layers in training)
layout(constant_id = 6) const bool ADJOINT = false;  // input adjoint's last chunk: times act'(below), dz^T too
layout(constant_id = 7) const uint ADJOINT_ACTIVATION = 0;  // NF_ACT_* of the layer below
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_activation.glsl"
#include "nf_rows.glsl"

layout(std430, binding = 0) buffer Output { vec4 y[]; };                   // [batch][out4]: nf_rows.glsl
layout(std430, binding = 1) writeonly buffer PreActivation { vec4 z[]; };  // when STORE_Z
layout(std430, binding = 2) writeonly buffer Transposed { float zt[]; };   // when ADJOINT: [row][zt_stride]
layout(std140, binding = 12) uniform Biases { vec4 b4[256]; };             // the layer's biases
layout(binding = 16) uniform samplerBuffer x;  // [batch][stride4]: nf_rows.glsl
layout(binding = 17) uniform samplerBuffer w;  // [out_dim][stride4] from vec4 w_base on
layout(binding = 18) uniform samplerBuffer below;  // when ADJOINT: the layer below's y (z for Sine), y's layout

layout(push_constant) uniform Push {
  uint batch;
  uint out4;  // output row length in vec4
  uint out_dim;
  uint blocks;  // row blocks of COLS rows: workgroup g takes block g % blocks of tile g / blocks
  float beta;
  float omega;
  uint has_bias;
  uint accumulate;  // add the earlier chunks' sums
  uint w_base;      // vec4 of the weights binding where row 0 starts
  uint stride4;     // vec4 per input row: between rows of x and between weight rows
  uint x_first4;    // first input vec4 of this chunk
  uint x_interleaved;  // nf_rows.glsl layouts of x and of y (and z)
  uint y_interleaved;
  uint zt_stride;  // floats per row of zt
} pc;

shared vec4 w_block[COLS * IN4];  // this workgroup's rows of the chunk, row-major

void main() {
  const uint group = nf_linear_group();
  const uint row_first = (group % pc.blocks) * COLS, tile = group / pc.blocks;
  const uint last_row = pc.out_dim - 1u;

  for (uint i = gl_LocalInvocationID.x; i < COLS * IN4; i += WG) {
    const uint c = i / IN4, k4 = i - c * IN4;
    w_block[i] = texelFetch(w, int(pc.w_base + min(row_first + c, last_row) * pc.stride4 + pc.x_first4 + k4));
  }
  barrier();

  // Eight neighbouring invocations take eight neighbouring samples, SAMPLES times.
  const uint index = tile * WG + gl_LocalInvocationID.x;
  const uint first_sample = (index / NF_ROW_GROUP) * NF_ROW_GROUP * SAMPLES + index % NF_ROW_GROUP;
  uint s[SAMPLES];  // this invocation's samples, clamped into the batch for reading
  [[unroll]] for (uint t = 0u; t < SAMPLES; ++t) s[t] = min(first_sample + NF_ROW_GROUP * t, pc.batch - 1u);
  const bool x_interleaved = pc.x_interleaved != 0u, y_interleaved = pc.y_interleaved != 0u;

  float acc[SAMPLES][COLS];
  [[unroll]] for (uint c = 0u; c < COLS; ++c) {
    // Without biases the binding is a small placeholder: read its first entry (and discard it).
    const uint o = pc.has_bias != 0u ? min(row_first + c, last_row) : 0u;
    const float bias = pc.has_bias != 0u ? b4[o >> 2][o & 3u] : 0.0;
    [[unroll]] for (uint t = 0u; t < SAMPLES; ++t) acc[t][c] = bias;
  }
  [[unroll]] for (uint k4 = 0u; k4 < IN4; ++k4) {
    vec4 xv[SAMPLES];
    [[unroll]] for (uint t = 0u; t < SAMPLES; ++t) xv[t] = texelFetch(x, int(nf_row_index(s[t], pc.x_first4 + k4, pc.stride4, x_interleaved)));
    [[unroll]] for (uint c = 0u; c < COLS; ++c) {
      const vec4 wv = w_block[c * IN4 + k4];
      [[unroll]] for (uint t = 0u; t < SAMPLES; ++t)
        acc[t][c] = fma(xv[t].x, wv.x, fma(xv[t].y, wv.y, fma(xv[t].z, wv.z, fma(xv[t].w, wv.w, acc[t][c]))));
    }
  }
  const uint rows = min(COLS, pc.out_dim - row_first);
  [[unroll]] for (uint t = 0u; t < SAMPLES; ++t) {
    [[unroll]] for (uint j = 0u; j < COLS / 4u; ++j) {
      const uint o = row_first + 4u * j;
      const uint i = nf_row_index(s[t], min(o, 4u * pc.out4 - 4u) / 4u, pc.out4, y_interleaved);
      vec4 pre = vec4(acc[t][4u * j], acc[t][4u * j + 1u], acc[t][4u * j + 2u], acc[t][4u * j + 3u]);
      if (4u * j < rows && first_sample + NF_ROW_GROUP * t < pc.batch) {
        // The earlier chunks' sums, by storage load under the branch: the first chunk skips it.
        if (pc.accumulate != 0u) pre += y[i];
        vec4 post;
        if (ADJOINT) {
          const vec4 v = texelFetch(below, int(i));
          [[unroll]] for (uint e = 0u; e < 4u; ++e) {
            const float d = nf_activate_derivative_kept(ADJOINT_ACTIVATION, pc.beta, pc.omega, v[e]);
            post[e] = o + e < pc.out_dim ? pre[e] * d : 0.0;
          }
          [[unroll]] for (uint e = 0u; e < 4u; ++e)
            if (o + e < pc.out_dim) zt[(o + e) * pc.zt_stride + first_sample + NF_ROW_GROUP * t] = post[e];
        } else {
          [[unroll]] for (uint e = 0u; e < 4u; ++e) {
            const bool real = o + e < pc.out_dim;  // padding columns stay zero
            pre[e] = real ? pre[e] : 0.0;
            post[e] = real ? nf_activate(ACTIVATION, pc.beta, pc.omega, pre[e]) : 0.0;
          }
        }
        y[i] = post;
        if (STORE_Z) z[i] = pre;
      }
    }
  }
}
