#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// One MLP layer for a block of COLS output rows: y = act(W x + b), for SAMPLES samples per
// invocation, reading four features at a time; COLS x SAMPLES outputs stay in registers. Weights
// and biases sit in uniform buffers that every lane reads at the same offset. The body is
// straight-line code on purpose: lavapipe (Mesa 22.3) loads a value once and broadcasts it only
// when its offset is built from constants and push constants *and* the load sits outside any loop,
// branch or early return; anywhere else every lane loads on its own. Even then each weight load
// costs a bounds check and a branch, so on CPU devices every weight feeds two samples (c8s2: more
// accumulators would spill); GPUs broadcast uniform loads anyway and take one sample per
// invocation (c32s1). Inputs come by texel fetch, a straight-line gather, where a storage-buffer
// load loops over the lanes. The input loop is unrolled (IN4 is a specialisation constant), the
// tail lanes are clamped instead of returning, and only the stores are conditional. LLVM's compile
// time grows faster than the body (8 s for 2048 multiply-adds, 40 s for twice that), so a dispatch
// covers a chunk of at most 16 input vec4 and later chunks add to y; the bias enters with the
// first chunk, the activation with the last (a specialisation constant: lavapipe evaluates both
// sides of a branch, so a run-time switch would evaluate every activation).
// The same kernel computes the input adjoint dx = W^T dz, on transposed weights. One dispatch per
// block of COLS rows and input chunk. Layout: engine/nn/mlp_config.hpp. Host: engine/nn/mlp.cpp.
//! variant c8s2 -DCOLS=8 -DSAMPLES=2
//! variant c16s1 -DCOLS=16 -DSAMPLES=1
//! variant c32s1 -DCOLS=32 -DSAMPLES=1

layout(constant_id = 0) const uint WG = 64;
layout(constant_id = 3) const uint IN4 = 1;         // input vec4 in this dispatch's chunk
layout(constant_id = 4) const uint ACTIVATION = 0;  // NF_ACT_*: NONE but on a layer's last chunk
layout(constant_id = 5) const bool STORE_Z = false;  // keep pre-activations (Sine layers in training)
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_activation.glsl"
#include "nf_rows.glsl"

layout(std430, binding = 0) buffer Output { vec4 y[]; };                   // [batch][out4]: nf_rows.glsl
layout(std430, binding = 1) writeonly buffer PreActivation { vec4 z[]; };  // when STORE_Z
// This dispatch's rows, stride4 vec4 apart, from vec4 w_base on: the binding starts at an offset
// the device accepts and w_base covers the rest; it spans up to 64 KiB (less where the device's
// uniform range or the buffer ends sooner).
layout(std140, binding = 12) uniform Weights { vec4 w[4096]; };
layout(std140, binding = 13) uniform Biases { vec4 b4[256]; };  // the layer's biases
layout(binding = 16) uniform samplerBuffer x;                   // [batch][x_stride4]: nf_rows.glsl

layout(push_constant) uniform Push {
  uint batch;
  uint out4;       // output row length in vec4
  uint out_dim;
  uint row_first;  // first output row of this dispatch (a multiple of 4)
  uint rows;       // rows in this dispatch (<= COLS)
  float beta;
  float omega;
  uint has_bias;
  uint accumulate;  // add the earlier chunks' sums
  uint w_base;      // first vec4 of this dispatch's block in the weights binding
  uint stride4;     // vec4 per input row: between rows of x and between weight rows
  uint x_first4;    // first input vec4 of this chunk
  uint x_interleaved;  // nf_rows.glsl layouts of x and of y (and z)
  uint y_interleaved;
} pc;

void main() {
  // Eight neighbouring invocations take eight neighbouring samples, SAMPLES times.
  const uint index = nf_linear_index();
  const uint first_sample = (index / NF_ROW_GROUP) * NF_ROW_GROUP * SAMPLES + index % NF_ROW_GROUP;
  uint s[SAMPLES];  // this invocation's samples, clamped into the batch for reading
  [[unroll]] for (uint t = 0u; t < SAMPLES; ++t) s[t] = min(first_sample + NF_ROW_GROUP * t, pc.batch - 1u);
  const bool x_interleaved = pc.x_interleaved != 0u, y_interleaved = pc.y_interleaved != 0u;

  float acc[SAMPLES][COLS];
  [[unroll]] for (uint c = 0u; c < COLS; ++c) {
    // Without biases the binding is a small placeholder: read its first entry (and discard it).
    const uint o = pc.has_bias != 0u ? min(pc.row_first + c, pc.out_dim - 1u) : 0u;
    const float bias = pc.has_bias != 0u ? b4[o >> 2][o & 3u] : 0.0;
    [[unroll]] for (uint t = 0u; t < SAMPLES; ++t) acc[t][c] = bias;
  }
  [[unroll]] for (uint k4 = 0u; k4 < IN4; ++k4) {
    vec4 xv[SAMPLES];
    [[unroll]] for (uint t = 0u; t < SAMPLES; ++t) xv[t] = texelFetch(x, int(nf_row_index(s[t], pc.x_first4 + k4, pc.stride4, x_interleaved)));
    [[unroll]] for (uint c = 0u; c < COLS; ++c) {
      const vec4 wv = w[pc.w_base + min(c, pc.rows - 1u) * pc.stride4 + k4];
      [[unroll]] for (uint t = 0u; t < SAMPLES; ++t)
        acc[t][c] = fma(xv[t].x, wv.x, fma(xv[t].y, wv.y, fma(xv[t].z, wv.z, fma(xv[t].w, wv.w, acc[t][c]))));
    }
  }
  [[unroll]] for (uint t = 0u; t < SAMPLES; ++t) {
    [[unroll]] for (uint j = 0u; j < COLS / 4u; ++j) {
      const uint o = pc.row_first + 4u * j;
      const uint i = nf_row_index(s[t], min(o, 4u * pc.out4 - 4u) / 4u, pc.out4, y_interleaved);
      vec4 pre = vec4(acc[t][4u * j], acc[t][4u * j + 1u], acc[t][4u * j + 2u], acc[t][4u * j + 3u]);
      if (4u * j < pc.rows && first_sample + NF_ROW_GROUP * t < pc.batch) {
        // The earlier chunks' sums, by storage load under the branch: the first chunk skips it
        // entirely, where a texel fetch would read for every chunk (the two measured the same).
        if (pc.accumulate != 0u) pre += y[i];
        vec4 post;
        [[unroll]] for (uint e = 0u; e < 4u; ++e) {
          const bool real = o + e < pc.out_dim;  // padding columns stay zero
          pre[e] = real ? pre[e] : 0.0;
          post[e] = real ? nf_activate(ACTIVATION, pc.beta, pc.omega, pre[e]) : 0.0;
        }
        y[i] = post;
        if (STORE_Z) z[i] = pre;
      }
    }
  }
}
