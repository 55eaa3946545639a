#include "engine/nn/init.hpp"

#include <cmath>
#include <random>

#include "engine/core/error.hpp"

namespace nf::nn {

std::vector<float> initial_parameters(const MlpConfig& config, const InitOptions& options) {
  config.validate();
  const auto layers = config.layers();
  std::vector<float> p(config.parameter_count(), 0.f);
  std::mt19937 rng(options.seed);
  const auto weight = [&](const LayerShape& l, std::uint32_t o, std::uint32_t k) -> float& {
    return p[l.weight_offset + std::uint64_t(o) * l.in_stride + k];
  };
  if (options.scheme == InitScheme::Geometric && options.position_columns > config.input_dim)
    throw InputError("geometric init: position_columns exceeds the input dimension");
  const double pi = 3.14159265358979323846;
  for (std::size_t li = 0; li < layers.size(); ++li) {
    const LayerShape& l = layers[li];
    const bool last = li + 1 == layers.size();
    for (std::uint32_t o = 0; o < l.out; ++o) {
      for (std::uint32_t k = 0; k < l.in; ++k) {
        float& w = weight(l, o, k);
        switch (options.scheme) {
          case InitScheme::KaimingUniform: {
            const double b = 1.0 / std::sqrt(double(l.in));
            w = float(std::uniform_real_distribution<double>(-b, b)(rng));
            break;
          }
          case InitScheme::KaimingNormal:
            w = float(std::normal_distribution<double>(0.0, std::sqrt(2.0 / l.in))(rng));
            break;
          case InitScheme::Siren: {
            const double b = li == 0 ? 1.0 / l.in : std::sqrt(6.0 / l.in) / config.hidden_activation.omega;
            w = float(std::uniform_real_distribution<double>(-b, b)(rng));
            break;
          }
          case InitScheme::Geometric:
            if (last)
              w = o == 0 ? float(std::normal_distribution<double>(std::sqrt(pi) / std::sqrt(double(l.in)), 1e-4)(rng)) : 0.f;
            else if (li == 0 && k >= options.position_columns)
              w = 0.f;  // encoding features start silent: the sphere comes from the raw position
            else
              w = float(std::normal_distribution<double>(0.0, std::sqrt(2.0) / std::sqrt(double(l.out)))(rng));
            break;
        }
      }
      float& b = p[l.bias_offset + o];
      switch (options.scheme) {
        case InitScheme::KaimingUniform:
        case InitScheme::Siren: {
          const double bound = 1.0 / std::sqrt(double(l.in));
          b = float(std::uniform_real_distribution<double>(-bound, bound)(rng));
          break;
        }
        case InitScheme::KaimingNormal: b = 0.f; break;
        case InitScheme::Geometric: b = last && o == 0 ? -options.radius : 0.f; break;
      }
    }
  }
  return p;
}

}  // namespace nf::nn
