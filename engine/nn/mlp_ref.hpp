#pragma once
// CPU reference of the MLP, forward and adjoint, one template for float and double. Tensors are
// feature-major like on the GPU: x[f * batch + s].
#include <cstdint>
#include <vector>

#include "engine/nn/activation_ref.hpp"
#include "engine/nn/mlp_config.hpp"

namespace nf::nn {

template <class T>
struct MlpTrace {
  std::vector<std::vector<T>> z;  // pre-activations per layer
  std::vector<std::vector<T>> y;  // post-activations per layer; y.back() is the output
};

template <class T>
MlpTrace<T> mlp_forward_ref(const MlpConfig& config, const std::vector<T>& params, const std::vector<T>& input,
                            std::uint32_t batch) {
  MlpTrace<T> trace;
  const std::vector<T>* x = &input;
  for (const LayerShape& l : config.layers()) {
    std::vector<T> z(std::size_t(l.out) * batch), y(z.size());
    for (std::uint32_t o = 0; o < l.out; ++o)
      for (std::uint32_t s = 0; s < batch; ++s) {
        T acc = params[l.bias_offset + o];
        for (std::uint32_t k = 0; k < l.in; ++k) acc += params[l.weight_offset + std::uint64_t(o) * l.in + k] * (*x)[std::size_t(k) * batch + s];
        z[std::size_t(o) * batch + s] = acc;
        y[std::size_t(o) * batch + s] = activate(l.activation, acc);
      }
    trace.z.push_back(std::move(z));
    trace.y.push_back(std::move(y));
    x = &trace.y.back();
  }
  return trace;
}

// Given dL/doutput, returns dL/dinput; dL/dparams is added into grad_params.
template <class T>
std::vector<T> mlp_backward_ref(const MlpConfig& config, const std::vector<T>& params, const std::vector<T>& input,
                                std::uint32_t batch, const MlpTrace<T>& trace, const std::vector<T>& grad_output,
                                std::vector<T>& grad_params) {
  const auto layers = config.layers();
  grad_params.resize(params.size(), T(0));
  std::vector<T> dy = grad_output;
  for (std::size_t li = layers.size(); li-- > 0;) {
    const LayerShape& l = layers[li];
    const std::vector<T>& x = li == 0 ? input : trace.y[li - 1];
    std::vector<T> dz(dy.size());
    for (std::size_t i = 0; i < dz.size(); ++i) dz[i] = dy[i] * activate_derivative(l.activation, trace.z[li][i]);
    std::vector<T> dx(std::size_t(l.in) * batch, T(0));
    for (std::uint32_t o = 0; o < l.out; ++o)
      for (std::uint32_t s = 0; s < batch; ++s) {
        const T g = dz[std::size_t(o) * batch + s];
        grad_params[l.bias_offset + o] += g;
        for (std::uint32_t k = 0; k < l.in; ++k) {
          grad_params[l.weight_offset + std::uint64_t(o) * l.in + k] += g * x[std::size_t(k) * batch + s];
          dx[std::size_t(k) * batch + s] += g * params[l.weight_offset + std::uint64_t(o) * l.in + k];
        }
      }
    dy = std::move(dx);
  }
  return dy;
}

}  // namespace nf::nn
