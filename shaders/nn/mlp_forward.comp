#version 460
#extension GL_GOOGLE_include_directive : require
// One MLP layer: y = act(W x + b) for a batch. Lanes run over samples, so every lane of a subgroup
// reads the same weight (a broadcast) and neighbouring samples of each feature (a vector load).
// Each invocation keeps ROWS samples x COLS outputs in registers. Host: engine/nn/mlp.cpp.
//! variant r2c4 -DROWS=2 -DCOLS=4
//! variant r4c4 -DROWS=4 -DCOLS=4
//! variant r2c8 -DROWS=2 -DCOLS=8
//! variant r1c8 -DROWS=1 -DCOLS=8

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_activation.glsl"

layout(std430, binding = 0) readonly buffer Input { float x[]; };
layout(std430, binding = 1) readonly buffer Params { float params[]; };
layout(std430, binding = 2) writeonly buffer Output { float y[]; };
layout(std430, binding = 3) writeonly buffer PreActivation { float z_out[]; };  // Sine layers in training

layout(push_constant) uniform Push {
  uint batch;
  uint in_dim;
  uint out_dim;
  uint weight_offset;
  uint bias_offset;
  uint activation;
  float beta;
  float omega;
  uint store_z;              // also write the pre-activation
  uint input_sample_major;   // x[s * in_dim + k] instead of x[k * batch + s]
  uint output_sample_major;  // y[s * out_dim + o] instead of y[o * batch + s]
} pc;

void main() {
  const uint base = nf_linear_group() * WG * ROWS + gl_LocalInvocationID.x;
  if (base >= pc.batch) return;
  uint s[ROWS];
  for (uint r = 0u; r < ROWS; ++r) s[r] = min(base + r * WG, pc.batch - 1u);  // tail lanes redo a valid sample
  for (uint ob = 0u; ob < pc.out_dim; ob += COLS) {
    float acc[ROWS][COLS];
    for (uint c = 0u; c < COLS; ++c) {
      const float b = params[pc.bias_offset + min(ob + c, pc.out_dim - 1u)];
      for (uint r = 0u; r < ROWS; ++r) acc[r][c] = b;
    }
    for (uint k = 0u; k < pc.in_dim; ++k) {
      float xv[ROWS];
      for (uint r = 0u; r < ROWS; ++r)
        xv[r] = pc.input_sample_major != 0u ? x[s[r] * pc.in_dim + k] : x[k * pc.batch + s[r]];
      for (uint c = 0u; c < COLS; ++c) {
        const float w = params[pc.weight_offset + min(ob + c, pc.out_dim - 1u) * pc.in_dim + k];
        for (uint r = 0u; r < ROWS; ++r) acc[r][c] = fma(xv[r], w, acc[r][c]);
      }
    }
    for (uint r = 0u; r < ROWS; ++r) {
      if (base + r * WG >= pc.batch) continue;
      for (uint c = 0u; c < COLS; ++c) {
        const uint o = ob + c;
        if (o >= pc.out_dim) continue;
        const float z = acc[r][c];
        const uint i = pc.output_sample_major != 0u ? s[r] * pc.out_dim + o : o * pc.batch + s[r];
        y[i] = nf_activate(pc.activation, pc.beta, pc.omega, z);
        if (pc.store_z != 0u) z_out[o * pc.batch + s[r]] = z;
      }
    }
  }
}
