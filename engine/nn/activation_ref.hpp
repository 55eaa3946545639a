#pragma once
// Activations and their derivatives, CPU twin of shaders/include/nf_activation.glsl.
// Softplus(beta) switches to the identity above beta*x = 20 (where log1p(exp(t)) == t in float)
// so large arguments neither overflow nor lose the gradient.
#include <cmath>

#include "engine/nn/mlp_config.hpp"

namespace nf::nn {

constexpr double kSoftplusLinear = 20.0;

template <class T>
T activate(const ActivationSpec& a, T z) {
  switch (a.type) {
    case Activation::ReLU: return z > T(0) ? z : T(0);
    case Activation::Softplus: {
      const T t = T(a.beta) * z;
      return t > T(kSoftplusLinear) ? z : std::log1p(std::exp(t)) / T(a.beta);
    }
    case Activation::Sine: return std::sin(T(a.omega) * z);
    case Activation::None: break;
  }
  return z;
}

// d activate / dz, from z.
template <class T>
T activate_derivative(const ActivationSpec& a, T z) {
  switch (a.type) {
    case Activation::ReLU: return z > T(0) ? T(1) : T(0);
    case Activation::Softplus: {
      const T t = T(a.beta) * z;
      return t > T(kSoftplusLinear) ? T(1) : T(1) / (T(1) + std::exp(-t));
    }
    case Activation::Sine: return T(a.omega) * std::cos(T(a.omega) * z);
    case Activation::None: break;
  }
  return T(1);
}

}  // namespace nf::nn
