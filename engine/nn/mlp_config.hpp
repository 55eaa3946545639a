#pragma once
// Shape of a multilayer perceptron: layer widths, activations and where each layer's parameters
// live in one flat parameter array (per layer: weights [out][in] row-major, then biases [out]).
// Activations and batches are feature-major on the GPU: a tensor of F features for B samples is
// F rows of B floats, so consecutive invocations (samples) touch consecutive addresses.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/json.hpp"

namespace nf::nn {

enum class Activation : std::uint32_t { None = 0, ReLU = 1, Softplus = 2, Sine = 3 };

struct ActivationSpec {
  Activation type = Activation::ReLU;
  float beta = 100.f;   // Softplus(beta): log(1 + exp(beta x)) / beta
  float omega = 30.f;   // Sine (SIREN): sin(omega x)
};

struct LayerShape {
  std::uint32_t in = 0, out = 0;
  std::uint64_t weight_offset = 0, bias_offset = 0;  // in floats, into the parameter array
  ActivationSpec activation;
};

struct MlpConfig {
  std::uint32_t input_dim = 0;
  std::vector<std::uint32_t> hidden;  // widths of the hidden layers
  std::uint32_t output_dim = 0;
  ActivationSpec hidden_activation;
  ActivationSpec output_activation{Activation::None};

  std::vector<LayerShape> layers() const;
  std::uint64_t parameter_count() const;
  std::uint32_t max_width() const;
  // Throws InputError naming the field: dims 1..1024, hidden widths 1..kMaxWidth, finite beta/omega.
  void validate() const;
};

constexpr std::uint32_t kMaxWidth = 1024;

std::string to_string(Activation a);
Activation activation_from_string(const std::string& name);  // throws InputError
json to_json(const MlpConfig& config);
MlpConfig mlp_config_from_json(const json& j);  // throws InputError naming the field

}  // namespace nf::nn
