#pragma once
// Parameter initialisation for an Mlp, in its layout (padding and alignment gaps stay zero).
//   kaiming_uniform: PyTorch's default for Linear, U(+-1/sqrt(in)) for weights and biases;
//   kaiming_normal:  N(0, sqrt(2/in)) weights, zero biases (ReLU nets);
//   siren:           Sitzmann et al.: first layer U(+-1/in), later U(+-sqrt(6/in)/omega);
//   geometric:       Atzmon & Lipman (SAL), as in NeuS: the net starts as the SDF of a sphere of
//                    `radius` about the origin of its first `position_columns` inputs (outputs
//                    after the first are zero at start); other input columns start at zero weight.
#include <cstdint>
#include <vector>

#include "engine/nn/mlp_config.hpp"

namespace nf::nn {

enum class InitScheme { KaimingUniform, KaimingNormal, Siren, Geometric };

struct InitOptions {
  InitScheme scheme = InitScheme::KaimingUniform;
  unsigned seed = 1;
  float radius = 0.5f;                 // geometric
  std::uint32_t position_columns = 3;  // geometric: inputs that hold the raw position
};

std::vector<float> initial_parameters(const MlpConfig& config, const InitOptions& options);

}  // namespace nf::nn
