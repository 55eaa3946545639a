#version 460
#extension GL_GOOGLE_include_directive : require
// Optimiser step, pass 2 (one invocation): reduce the gradient statistics and decide on the GPU,
// without a round trip to the host, whether this step is taken (all gradients finite) and by how
// much the gradients are scaled (global-norm clipping). Counts taken and skipped steps.

layout(local_size_x = 1) in;

layout(std430, binding = 0) readonly buffer Partials { vec2 partials[]; };
layout(std430, binding = 1) buffer State {
  uint taken;     // steps applied (bias correction uses this)
  uint skipped;   // steps skipped for non-finite gradients
  uint skip;      // this step is skipped
  float clip;     // gradient scale of this step
  float norm;     // global gradient norm of this step (finite part)
  float beta1_t;  // beta1^taken and beta2^taken, kept as running products: GLSL pow is too coarse
  float beta2_t;  // for 1 - beta^t near beta = 0.999
} state;

layout(push_constant) uniform Push {
  uint groups;
  float max_norm;  // 0: no clipping
  float beta1;
  float beta2;
} pc;

void main() {
  vec2 s = vec2(0.0);
  for (uint i = 0u; i < pc.groups; ++i) s += partials[i];
  state.norm = sqrt(s.x);
  if (s.y > 0.0) {
    state.skip = 1u;
    state.skipped += 1u;
    state.clip = 0.0;
    return;
  }
  state.skip = 0u;
  state.taken += 1u;
  state.beta1_t *= pc.beta1;
  state.beta2_t *= pc.beta2;
  state.clip = pc.max_norm > 0.0 && state.norm > pc.max_norm ? pc.max_norm / state.norm : 1.0;
}
