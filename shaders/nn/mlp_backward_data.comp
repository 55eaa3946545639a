#version 460
#extension GL_GOOGLE_include_directive : require
// Adjoint of one layer with respect to its input: dx = W^T dz. Same layout as mlp_forward: lanes
// over samples, weights broadcast, ROWS samples x COLS inputs per invocation.
//! variant r2c4 -DROWS=2 -DCOLS=4
//! variant r4c4 -DROWS=4 -DCOLS=4
//! variant r2c8 -DROWS=2 -DCOLS=8
//! variant r1c8 -DROWS=1 -DCOLS=8

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer GradZ { float dz[]; };  // out_dim x batch
layout(std430, binding = 1) readonly buffer Params { float params[]; };
layout(std430, binding = 2) buffer GradX { float dx[]; };

layout(push_constant) uniform Push {
  uint batch;
  uint in_dim;
  uint out_dim;
  uint weight_offset;
  uint output_sample_major;  // dx[s * in_dim + k] (gradient of raw, sample-major inputs)
  uint accumulate;           // add to dx instead of overwriting
} pc;

void main() {
  const uint base = nf_linear_group() * WG * ROWS + gl_LocalInvocationID.x;
  if (base >= pc.batch) return;
  uint s[ROWS];
  for (uint r = 0u; r < ROWS; ++r) s[r] = min(base + r * WG, pc.batch - 1u);
  for (uint kb = 0u; kb < pc.in_dim; kb += COLS) {
    float acc[ROWS][COLS];
    for (uint r = 0u; r < ROWS; ++r)
      for (uint c = 0u; c < COLS; ++c) acc[r][c] = 0.0;
    for (uint o = 0u; o < pc.out_dim; ++o) {
      float g[ROWS];
      for (uint r = 0u; r < ROWS; ++r) g[r] = dz[o * pc.batch + s[r]];
      for (uint c = 0u; c < COLS; ++c) {
        const float w = params[pc.weight_offset + o * pc.in_dim + min(kb + c, pc.in_dim - 1u)];
        for (uint r = 0u; r < ROWS; ++r) acc[r][c] = fma(g[r], w, acc[r][c]);
      }
    }
    for (uint r = 0u; r < ROWS; ++r) {
      if (base + r * WG >= pc.batch) continue;
      for (uint c = 0u; c < COLS; ++c) {
        const uint k = kb + c;
        if (k >= pc.in_dim) continue;
        const uint i = pc.output_sample_major != 0u ? s[r] * pc.in_dim + k : k * pc.batch + s[r];
        dx[i] = pc.accumulate != 0u ? dx[i] + acc[r][c] : acc[r][c];
      }
    }
  }
}
