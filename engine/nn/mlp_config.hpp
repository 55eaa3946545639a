#pragma once
// Shape of a multilayer perceptron: layer widths, activations and where each layer's parameters
// live in one flat parameter array.
//
// Layout (shared by the GPU kernels and the CPU reference):
// - a batch of F features is B rows of pad4(F) floats (sample-major; the padding holds zeros), so an
//   invocation reads its sample's features four at a time (inside an Mlp the hidden layers'
//   tensors are lane-interleaved instead: shaders/include/nf_rows.glsl);
// - per layer: weights [out][pad4(in)] row-major (padding columns zero), then biases [out]; both
//   blocks start on a multiple of 64 floats, so a layer's weights can be bound as a texel buffer and
//   its biases as a uniform buffer on any device (both offset alignments are at most 256 bytes).
//   Alignment gaps are unused zeros.
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

constexpr std::uint32_t pad4(std::uint32_t n) { return (n + 3u) & ~3u; }
constexpr std::uint64_t kLayerAlignment = 64;  // floats

struct LayerShape {
  std::uint32_t in = 0, out = 0;
  std::uint32_t in_stride = 0, out_stride = 0;  // pad4(in), pad4(out): row lengths of x and y
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
  // Throws InputError naming the field: dims 1..1024, hidden widths 1..kMaxWidth, finite beta/omega.
  void validate() const;
};

constexpr std::uint32_t kMaxWidth = 1024;

std::string to_string(Activation a);
Activation activation_from_string(const std::string& name);  // throws InputError
json to_json(const MlpConfig& config);
MlpConfig mlp_config_from_json(const json& j);  // throws InputError naming the field

}  // namespace nf::nn
