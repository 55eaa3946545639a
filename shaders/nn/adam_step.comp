#version 460
#extension GL_GOOGLE_include_directive : require
// Optimiser step, pass 3: AdamW with bias correction on one parameter group, reading the decision
// and the clipping scale of adam_prepare. Decoupled weight decay: p -= lr (m^ / (sqrt(v^) + eps) + wd p).

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) buffer Params { float params[]; };
layout(std430, binding = 1) readonly buffer Grads { float grads[]; };
layout(std430, binding = 2) buffer FirstMoment { float m[]; };
layout(std430, binding = 3) buffer SecondMoment { float v[]; };
layout(std430, binding = 4) readonly buffer State {
  uint taken;
  uint skipped;
  uint skip;
  float clip;
  float norm;
  float beta1_t;
  float beta2_t;
} state;

layout(push_constant) uniform Push {
  uint offset;
  uint count;
  float lr;
  float weight_decay;
  float beta1;
  float beta2;
  float eps;
} pc;

void main() {
  const uint j = nf_linear_index();
  if (j >= pc.count || state.skip != 0u) return;
  const uint i = pc.offset + j;
  const float g = grads[i] * state.clip;
  const float mi = pc.beta1 * m[i] + (1.0 - pc.beta1) * g;
  const float vi = pc.beta2 * v[i] + (1.0 - pc.beta2) * g * g;
  m[i] = mi;
  v[i] = vi;
  const float m_hat = mi / (1.0 - state.beta1_t);
  const float v_hat = vi / (1.0 - state.beta2_t);
  params[i] -= pc.lr * (m_hat / (sqrt(v_hat) + pc.eps) + pc.weight_decay * params[i]);
}
