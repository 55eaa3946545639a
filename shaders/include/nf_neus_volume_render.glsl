// NeuS per-sample alpha and its partials, shared by shaders/neus/volume_render_{fwd,bwd}.comp.
// Maths, guards and kink conventions: engine/neus/volume_render_ref.hpp (detail::sample).
#ifndef NF_NEUS_VOLUME_RENDER_GLSL
#define NF_NEUS_VOLUME_RENDER_GLSL

float nf_vr_sigmoid(float x) {  // no overflow for any x
  if (x >= 0.0) return 1.0 / (1.0 + exp(-x));
  const float e = exp(x);
  return e / (1.0 + e);
}
float nf_vr_sigmoid_derivative(float x) {
  const float e = exp(-abs(x));
  return e / ((1.0 + e) * (1.0 + e));
}

// alpha of one sample; with `partials`, also dalpha/dsdf, dalpha/dcos, dalpha/dinv_s in d.
float nf_vr_sample(float sdf, float cs, float dist, float s, float anneal, bool partials, out vec3 d) {
  d = vec3(0.0);
  const float iter_cos = -(max(0.5 - 0.5 * cs, 0.0) * (1.0 - anneal) + max(-cs, 0.0) * anneal);
  const float h = iter_cos * dist * 0.5;
  const float prev = sdf - h, next = sdf + h;
  const float p = nf_vr_sigmoid(prev * s), c = nf_vr_sigmoid(next * s);
  const float den = p + 1e-5;
  const float raw = (p - c + 1e-5) / den;
  if (!partials || raw < 0.0 || raw > 1.0) return clamp(raw, 0.0, 1.0);
  const float da_dp = c / (den * den), da_dc = -1.0 / den;
  const float sp = nf_vr_sigmoid_derivative(prev * s), sc = nf_vr_sigmoid_derivative(next * s);
  const float dprev = da_dp * s * sp, dnext = da_dc * s * sc;
  const float diter = 0.5 * (1.0 - anneal) * (cs < 1.0 ? 1.0 : 0.0) + anneal * (cs < 0.0 ? 1.0 : 0.0);
  d = vec3(dprev + dnext, (dnext - dprev) * 0.5 * dist * diter, da_dp * prev * sp + da_dc * next * sc);
  return raw;
}

#endif
