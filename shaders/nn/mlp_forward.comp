#version 460
#extension GL_GOOGLE_include_directive : require
// One MLP layer for a block of COLS output rows: y = act(W x + b). One sample per invocation, read
// four features at a time; COLS outputs stay in registers. Weights and biases sit in uniform
// buffers that every lane reads at the same offset: GPUs broadcast them, and on lavapipe this
// measured 1.6x faster than storage buffers. (Unrolling the input loop so that every offset is a
// compile-time constant did not help on lavapipe 22.3 and made pipelines take seconds to build.)
// The same kernel computes the input adjoint dx = W^T dz, on transposed weights. One dispatch per
// block of COLS rows. Layout: engine/nn/mlp_config.hpp. Host: engine/nn/mlp.cpp.
//! variant c8 -DCOLS=8
//! variant c16 -DCOLS=16

layout(constant_id = 0) const uint WG = 64;
layout(constant_id = 3) const uint IN4 = 1;  // input row length in vec4
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_activation.glsl"

layout(std430, binding = 0) readonly buffer Input { vec4 x[]; };           // [batch][IN4]
layout(std430, binding = 1) buffer Output { vec4 y[]; };                   // [batch][out4]
layout(std430, binding = 2) writeonly buffer PreActivation { vec4 z[]; };  // Sine layers in training
// This dispatch's rows [COLS][IN4], from vec4 w_base on: the binding starts at an offset the device
// accepts and the push constant covers the rest (up to 16 vec4 for a 256-byte alignment).
layout(std140, binding = 12) uniform Weights { vec4 w[COLS * IN4 + 16u]; };
layout(std140, binding = 13) uniform Biases { vec4 b4[256]; };             // the layer's biases

layout(push_constant) uniform Push {
  uint batch;
  uint out4;       // output row length in vec4
  uint out_dim;
  uint row_first;  // first output row of this dispatch (a multiple of 4)
  uint rows;       // rows in this dispatch (<= COLS)
  uint activation;
  float beta;
  float omega;
  uint store_z;
  uint has_bias;
  uint accumulate;  // add to y instead of overwriting
  uint w_base;      // first vec4 of this dispatch's rows in the weights binding
} pc;

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.batch) return;
  float acc[COLS];
  for (uint c = 0u; c < COLS; ++c) {
    const uint o = min(pc.row_first + c, pc.out_dim - 1u);
    acc[c] = pc.has_bias != 0u ? b4[o >> 2][o & 3u] : 0.0;
  }
  for (uint k4 = 0u; k4 < IN4; ++k4) {
    const vec4 xv = x[s * IN4 + k4];
    for (uint c = 0u; c < COLS; ++c) {
      const vec4 wv = w[pc.w_base + min(c, pc.rows - 1u) * IN4 + k4];
      acc[c] = fma(xv.x, wv.x, fma(xv.y, wv.y, fma(xv.z, wv.z, fma(xv.w, wv.w, acc[c]))));
    }
  }
  for (uint j = 0u; j < COLS / 4u; ++j) {
    if (4u * j >= pc.rows) break;
    const uint o = pc.row_first + 4u * j;
    vec4 pre = vec4(acc[4u * j], acc[4u * j + 1u], acc[4u * j + 2u], acc[4u * j + 3u]);
    const uint i = s * pc.out4 + (o >> 2);
    if (pc.accumulate != 0u) pre += y[i];
    vec4 post;
    for (uint e = 0u; e < 4u; ++e) {
      const bool real = o + e < pc.out_dim;  // padding columns stay zero
      pre[e] = real ? pre[e] : 0.0;
      post[e] = real ? nf_activate(pc.activation, pc.beta, pc.omega, pre[e]) : 0.0;
    }
    y[i] = post;
    if (pc.store_z != 0u) z[i] = pre;
  }
}
