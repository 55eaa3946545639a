#version 460
#extension GL_GOOGLE_include_directive : require
// Transposed copy of one layer's weights for the input adjoint: wt[k][o] = w[o][k], rows of
// out_stride floats (padding zero), so dx = W^T dz runs through mlp_fwd.

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Params { float params[]; };
layout(std430, binding = 1) writeonly buffer Transposed { float wt[]; };  // [in][out_stride]

layout(push_constant) uniform Push {
  uint in_dim;
  uint in_stride;
  uint out_dim;
  uint out_stride;
  uint weight_offset;
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.in_dim * pc.out_stride) return;
  const uint k = i / pc.out_stride, o = i % pc.out_stride;
  wt[i] = o < pc.out_dim ? params[pc.weight_offset + o * pc.in_stride + k] : 0.0;
}
