#include "engine/fur/fur_field_head_gradcheck.hpp"

#include <random>

#include "engine/fur/fur_field_head.hpp"

namespace nf::fur {
namespace {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

FurHeadShape shape_of(const Params& p) {
  return {std::uint32_t(p.at("strands")), std::uint32_t(p.at("latent")), std::uint32_t(p.at("in_stride")),
          std::uint32_t(p.at("latent_stride")), std::uint32_t(p.at("segments"))};
}

// MLP rows with the confidence's raw value at `q_scale` (large: softplus' flat and linear ends).
Case make_case(std::string name, std::uint32_t strands, std::uint32_t latent, std::uint32_t segments, double q_scale, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::uint32_t in_stride = (latent + 1 + 3) & ~3u, latent_stride = (latent + 3) & ~3u;
  std::vector<double> rows(std::size_t(strands) * in_stride);
  for (std::uint32_t s = 0; s < strands; ++s)
    for (std::uint32_t j = 0; j < in_stride; ++j) rows[std::size_t(s) * in_stride + j] = j == latent ? q_scale * u(rng) : u(rng);
  Case c;
  c.name = std::move(name);
  c.params = {{"strands", strands}, {"latent", latent}, {"in_stride", in_stride}, {"latent_stride", latent_stride}, {"segments", segments}};
  c.inputs = {std::move(rows)};
  c.step_double = {1e-6};
  c.step_float = {1e-2};
  return c;
}

class FurHeadCheck : public gradcheck::WithReference<FurHeadCheck> {
 public:
  std::string name() const override { return "fur/fur_field_head"; }
  std::vector<std::string> input_names() const override { return {"rows"}; }
  std::vector<std::string> output_names() const override { return {"latents", "confidence"}; }
  std::vector<Case> cases() const override {
    return {make_case("fur_field", 3, 64, 99, 2.0, 1), make_case("odd_latent", 2, 5, 7, 1.0, 2),
            make_case("saturated_confidence", 2, 8, 5, 60.0, 3)};
  }
  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    Arrays<T> out(2);
    fur_head_forward_ref(in[0], shape_of(p), out[0], out[1]);
    return out;
  }
  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& grad_out) const {
    Arrays<T> grad(1);
    fur_head_backward_ref(in[0], shape_of(p), grad_out[0], grad_out[1], grad[0]);
    return grad;
  }
  Arrays<float> device_forward(gpu::Context& context, const Params& p, const Arrays<float>& in) const override {
    FurHeadOutputs o = fur_head(context, shape_of(p), in[0]);
    return {std::move(o.latents), std::move(o.confidence)};
  }
  Arrays<float> device_backward(gpu::Context& context, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& grad_out) const override {
    return {fur_head_gradient(context, shape_of(p), in[0], grad_out[0], grad_out[1])};
  }
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_fur_head_check() { return std::make_unique<FurHeadCheck>(); }

}  // namespace nf::fur
