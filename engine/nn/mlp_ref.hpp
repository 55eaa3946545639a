#pragma once
// CPU reference of the MLP, forward and adjoint, one template for float and double, on exactly the
// GPU layout of mlp_config.hpp (sample-major rows padded to 4, padded weight rows). Padding columns
// are not part of the maths: inputs and weights hold zeros there, and their gradients are zero.
#include <cstdint>
#include <vector>

#include "engine/nn/activation_ref.hpp"
#include "engine/nn/mlp_config.hpp"

namespace nf::nn {

template <class T>
struct MlpTrace {
  std::vector<std::vector<T>> z;  // pre-activations per layer, [batch][out_stride]
  std::vector<std::vector<T>> y;  // post-activations per layer; y.back() is the output
};

template <class T>
MlpTrace<T> mlp_forward_ref(const MlpConfig& config, const std::vector<T>& params, const std::vector<T>& input,
                            std::uint32_t batch) {
  MlpTrace<T> trace;
  const std::vector<T>* x = &input;
  for (const LayerShape& l : config.layers()) {
    std::vector<T> z(std::size_t(l.out_stride) * batch, T(0)), y(z.size(), T(0));
    for (std::uint32_t s = 0; s < batch; ++s)
      for (std::uint32_t o = 0; o < l.out; ++o) {
        T acc = params[l.bias_offset + o];
        for (std::uint32_t k = 0; k < l.in; ++k)
          acc += params[l.weight_offset + std::uint64_t(o) * l.in_stride + k] * (*x)[std::size_t(s) * l.in_stride + k];
        z[std::size_t(s) * l.out_stride + o] = acc;
        y[std::size_t(s) * l.out_stride + o] = activate(l.activation, acc);
      }
    trace.z.push_back(std::move(z));
    trace.y.push_back(std::move(y));
    x = &trace.y.back();
  }
  return trace;
}

// Given dL/doutput ([batch][out_stride]), returns dL/dinput ([batch][in_stride]); dL/dparams is added
// into grad_params (resized to the parameter count).
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
    std::vector<T> dx(std::size_t(l.in_stride) * batch, T(0));
    for (std::uint32_t s = 0; s < batch; ++s)
      for (std::uint32_t o = 0; o < l.out; ++o) {
        const std::size_t i = std::size_t(s) * l.out_stride + o;
        const T g = dy[i] * activate_derivative(l.activation, trace.z[li][i]);
        grad_params[l.bias_offset + o] += g;
        for (std::uint32_t k = 0; k < l.in; ++k) {
          const std::uint64_t w = l.weight_offset + std::uint64_t(o) * l.in_stride + k;
          grad_params[w] += g * x[std::size_t(s) * l.in_stride + k];
          dx[std::size_t(s) * l.in_stride + k] += g * params[w];
        }
      }
    dy = std::move(dx);
  }
  return dy;
}

}  // namespace nf::nn
