#version 460
#extension GL_GOOGLE_include_directive : require
// dL/dz = dL/dy * act'(z) for one layer, elementwise over [batch][out_stride]; padding columns get
// zero. grad_y and grad_z may be the same range.

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_activation.glsl"

layout(std430, binding = 0) readonly buffer GradY { float grad_y[]; };
layout(std430, binding = 1) readonly buffer Y { float y[]; };
layout(std430, binding = 2) readonly buffer Z { float z[]; };  // read for Sine only
layout(std430, binding = 3) writeonly buffer GradZ { float grad_z[]; };

layout(push_constant) uniform Push {
  uint count;  // batch * out_stride
  uint out_dim;
  uint out_stride;
  uint activation;
  float beta;
  float omega;
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.count) return;
  if (i % pc.out_stride >= pc.out_dim) {
    grad_z[i] = 0.0;
    return;
  }
  float d = 1.0;
  if (pc.activation == NF_ACT_SINE) d = nf_activate_derivative(pc.activation, pc.beta, pc.omega, 0.0, z[i]);
  else if (pc.activation != NF_ACT_NONE) d = nf_activate_derivative(pc.activation, pc.beta, pc.omega, y[i], 0.0);
  grad_z[i] = grad_y[i] * d;
}
