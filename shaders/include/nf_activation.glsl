// Activations of engine/nn (CPU twin: engine/nn/activation_ref.hpp). Derivatives are taken from the
// activation's output y where that determines them (ReLU, Softplus), so training keeps one tensor
// per layer; Sine needs the pre-activation z as well.
#ifndef NF_ACTIVATION_GLSL
#define NF_ACTIVATION_GLSL

const uint NF_ACT_NONE = 0u;
const uint NF_ACT_RELU = 1u;
const uint NF_ACT_SOFTPLUS = 2u;
const uint NF_ACT_SINE = 3u;
const float NF_SOFTPLUS_LINEAR = 20.0;  // above beta*z = 20, log1p(exp(t)) == t in float

// log(1 + u) without losing small u.
float nf_log1p(float u) { return u < 1e-4 ? u * (1.0 - 0.5 * u) : log(1.0 + u); }

float nf_activate(uint type, float beta, float omega, float z) {
  if (type == NF_ACT_RELU) return max(z, 0.0);
  if (type == NF_ACT_SOFTPLUS) {
    const float t = beta * z;
    return t > NF_SOFTPLUS_LINEAR ? z : nf_log1p(exp(t)) / beta;
  }
  if (type == NF_ACT_SINE) return sin(omega * z);
  return z;
}

// d activation / dz, from y = activation(z) (and z itself for Sine).
float nf_activate_derivative(uint type, float beta, float omega, float y, float z) {
  if (type == NF_ACT_RELU) return y > 0.0 ? 1.0 : 0.0;
  if (type == NF_ACT_SOFTPLUS) {
    const float t = beta * y;  // sigmoid(beta z) = 1 - exp(-beta y)
    return t < 1e-3 ? t * (1.0 - 0.5 * t) : 1.0 - exp(-t);
  }
  if (type == NF_ACT_SINE) return omega * cos(omega * z);
  return 1.0;
}

// The same from the one tensor training keeps for it: the output y, or z for Sine.
float nf_activate_derivative_kept(uint type, float beta, float omega, float kept) {
  return type == NF_ACT_SINE ? nf_activate_derivative(type, beta, omega, 0.0, kept)
                             : nf_activate_derivative(type, beta, omega, kept, 0.0);
}

#endif
