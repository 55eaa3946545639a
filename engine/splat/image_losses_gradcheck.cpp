#include "engine/splat/image_losses_gradcheck.hpp"

#include <cmath>
#include <random>

#include "engine/splat/image_losses.hpp"

namespace nf::splat {
namespace {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

constexpr double kPi = kImageLossPi;

ImageSize size_of(const Params& p) { return {std::uint32_t(p.at("width")), std::uint32_t(p.at("height"))}; }

// The targets of a case are fixed by its parameters: mask (1/3 zero, 1/3 one, 1/3 soft), weight in
// [0.2, 1] (a fraction `zero_weight` of them 0), Gabor angle in [0, pi), confidence in [0.1, 2]
// (half as many zeros as weights).
Arrays<double> targets(const Params& p) {
  const std::uint64_t n = size_of(p).pixels();
  std::mt19937 rng(unsigned(p.at("seed")));
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Arrays<double> t(4, std::vector<double>(n));
  const double zero_weight = p.at("zero_weight");
  for (std::uint64_t i = 0; i < n; ++i) {
    const double kind = u(rng);
    t[0][i] = kind < 1.0 / 3 ? 0.0 : kind < 2.0 / 3 ? 1.0 : u(rng);
    t[1][i] = u(rng) < zero_weight ? 0.0 : 0.2 + 0.8 * u(rng);
    t[2][i] = kPi * u(rng);
    t[3][i] = u(rng) < 0.5 * zero_weight ? 0.0 : 0.1 + 1.9 * u(rng);
  }
  for (auto& a : t)
    for (double& x : a) x = double(float(x));  // float and double references see the same targets
  return t;
}

// Inputs away from the kinks: |alpha - mask| >= 0.05, the rendered angle 0.1 rad or more from the
// Gabor angle and from the fold at pi/2, |o| in [0.2, 1]. tau in [0.05, 1], or with `tau_floor`
// set, a third below the floor (2e-5..7e-5), a third just above it (3e-4..6e-4).
Arrays<double> inputs(const Params& p) {
  const auto t = targets(p);
  const std::uint64_t n = size_of(p).pixels();
  std::mt19937 rng(unsigned(p.at("seed")) + 1000);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Arrays<double> in{std::vector<double>(n), std::vector<double>(2 * n), std::vector<double>(n)};
  for (std::uint64_t i = 0; i < n; ++i) {
    const double mask = t[0][i], d = 0.05 + 0.35 * u(rng);
    const bool up = mask + d <= 1.0 && (mask - d < 0.0 || u(rng) < 0.5);
    in[0][i] = up ? mask + d : mask - d;
    const double delta = (0.1 + (kPi / 2 - 0.2) * u(rng)) * (u(rng) < 0.5 ? -1 : 1);
    const double theta = t[2][i] + delta, m = 0.2 + 0.8 * u(rng);
    in[1][i] = m * std::cos(2 * theta);
    in[1][n + i] = m * std::sin(2 * theta);
    const double which = u(rng);
    if (p.at("tau_floor") > 0 && which < 1.0 / 3)
      in[2][i] = 2e-5 + 5e-5 * u(rng);
    else if (p.at("tau_floor") > 0 && which < 2.0 / 3)
      in[2][i] = 3e-4 + 3e-4 * u(rng);
    else
      in[2][i] = 0.05 + 0.95 * u(rng);
  }
  return in;
}

Case make_case(std::string name, std::uint32_t width, std::uint32_t height, unsigned seed, double zero_weight,
               bool tau_floor) {
  Case c;
  c.name = std::move(name);
  c.params = {{"width", width},
              {"height", height},
              {"seed", seed},
              {"zero_weight", zero_weight},
              {"tau_floor", tau_floor ? 1.0 : 0.0}};
  c.inputs = inputs(c.params);
  c.step_double = {1e-6, 1e-6, tau_floor ? 1e-9 : 1e-6};
  // alpha: piecewise linear, exact. o: 4e-3 turns the angle by at most 1e-2 rad (|o| >= 0.2), far
  // inside the 0.1 rad margin, and beats float's noise on the summed loss. Near the floor tau moves
  // by 2e-5: the pixels below it stay below, those above stay above.
  c.step_float = {1e-3, 4e-3, tau_floor ? 2e-5 : 1e-3};
  return c;
}

class ImageLossesCheck : public gradcheck::WithReference<ImageLossesCheck> {
 public:
  std::string name() const override { return "splat/image_losses"; }
  std::vector<std::string> input_names() const override { return {"alpha", "orientation", "tau"}; }
  std::vector<std::string> output_names() const override { return {"L_sil", "L_dir"}; }

  std::vector<Case> cases() const override {
    std::vector<Case> cases;
    cases.push_back(make_case("random_7x5", 7, 5, 3, 0.0, false));
    cases.push_back(make_case("weight_zeros_6x6", 6, 6, 4, 0.4, false));
    cases.push_back(make_case("tau_floor_5x4", 5, 4, 5, 0.0, true));
    {  // alpha exactly on the mask at a third of the pixels: the |.| kink, subgradient 0.
      Case c = make_case("alpha_on_mask", 5, 3, 6, 0.2, false);
      const auto t = targets(c.params);
      for (std::size_t i = 0; i < c.inputs[0].size(); i += 3) c.inputs[0][i] = t[0][i];
      c.step_double[0] = c.step_float[0] = 0;
      c.skip_reason = "kink: alpha == mask, subgradient sign(0) = 0 is not a difference quotient";
      cases.push_back(c);
    }
    return cases;
  }

  template <class T>
  static ImageLossTargets<T> view(const std::vector<std::vector<T>>& t) {
    return {t[0], t[1], t[2], t[3]};
  }
  template <class T>
  static ImageLossInputs<T> view_inputs(const Arrays<T>& in) {
    return {in[0], in[1], in[2]};
  }
  template <class T>
  static std::vector<std::vector<T>> targets_as(const Params& p) {
    const auto t = targets(p);
    std::vector<std::vector<T>> out(t.size());
    for (std::size_t a = 0; a < t.size(); ++a) out[a].assign(t[a].begin(), t[a].end());
    return out;
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    const auto t = targets_as<T>(p);
    const auto v = image_losses_forward_ref<T>(size_of(p).pixels(), view_inputs(in), view(t), ImageLossParams{});
    return {{v.silhouette}, {v.orientation}};
  }

  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& g) const {
    const auto t = targets_as<T>(p);
    const std::uint64_t n = size_of(p).pixels();
    const ImageLossParams params;
    const auto v = image_losses_forward_ref<T>(n, view_inputs(in), view(t), params);
    auto grads = image_losses_backward_ref<T>(n, view_inputs(in), view(t), params, v, g[0][0], g[1][0]);
    return {std::move(grads.alpha), std::move(grads.orientation), std::move(grads.tau)};
  }

  Arrays<float> device_forward(gpu::Context& ctx, const Params& p, const Arrays<float>& in) const override {
    const auto t = targets_as<float>(p);
    const auto v = image_losses(ctx, size_of(p), view_inputs(in), view(t));
    return {{v.silhouette}, {v.orientation}};
  }

  Arrays<float> device_backward(gpu::Context& ctx, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& g) const override {
    const auto t = targets_as<float>(p);
    auto r = image_losses_with_gradients(ctx, size_of(p), view_inputs(in), view(t), g[0][0], g[1][0]);
    return {std::move(r.grads.alpha), std::move(r.grads.orientation), std::move(r.grads.tau)};
  }
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_image_losses_check() {
  return std::make_unique<ImageLossesCheck>();
}

}  // namespace nf::splat
