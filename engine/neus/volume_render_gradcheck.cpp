#include "engine/neus/volume_render_gradcheck.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "engine/neus/volume_render.hpp"

namespace nf::neus {
namespace {

using gradcheck::Arrays;
using gradcheck::Case;
using gradcheck::Params;

std::uint64_t rays_of(const Params& p) { return std::uint64_t(p.at("rays")); }
std::uint32_t samples_of(const Params& p) { return std::uint32_t(p.at("samples")); }

// Section lengths (not differentiated): the ray [0, 2] cut into S sections of jittered length.
std::vector<double> dists(const Params& p) {
  const std::uint64_t n = rays_of(p) * samples_of(p);
  std::mt19937 rng(unsigned(p.at("seed")) + 7);
  std::uniform_real_distribution<double> u(0.8, 1.2);
  std::vector<double> d(n);
  for (double& x : d) x = double(float(2.0 / samples_of(p) * u(rng)));
  return d;
}

// A ray entering a surface: sdf_i = (t_c - t_i) |cos_i| + noise, crossing zero mid-ray; cos_i in
// [-0.9, -0.2] (0.2 from the relu kinks at 0 and, for the 0.5 cos - 0.5 branch, at 1); rgb in [0, 1].
// alpha's clamp is never active (iter_cos <= 0 gives p >= c).
Arrays<double> inputs(const Params& p, double inv_s) {
  const std::uint64_t rays = rays_of(p);
  const std::uint32_t s = samples_of(p);
  const auto d = dists(p);
  std::mt19937 rng(unsigned(p.at("seed")));
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Arrays<double> in{std::vector<double>(rays * s), std::vector<double>(rays * s), std::vector<double>(rays * s * 3),
                    {inv_s}};
  for (std::uint64_t r = 0; r < rays; ++r) {
    const double tc = 0.6 + 0.8 * u(rng);
    double t = 0;
    for (std::uint32_t i = 0; i < s; ++i) {
      const std::uint64_t k = r * s + i;
      const double mid = t + 0.5 * d[k];
      t += d[k];
      const double cs = -0.2 - 0.7 * u(rng);
      in[1][k] = cs;
      in[0][k] = (tc - mid) * std::fabs(cs) + 0.01 * (u(rng) - 0.5);
      for (int ch = 0; ch < 3; ++ch) in[2][k * 3 + ch] = u(rng);
    }
  }
  for (auto& a : in)
    for (double& x : a) x = double(float(x));
  return in;
}

Case make_case(std::string name, std::uint32_t rays, std::uint32_t samples, unsigned seed, double inv_s,
               double anneal) {
  Case c;
  c.name = std::move(name);
  c.params = {{"rays", rays}, {"samples", samples}, {"seed", seed}, {"cos_anneal", anneal}};
  c.inputs = inputs(c.params, inv_s);
  // Double: steps scale with the sigmoid's width 1/inv_s (relative truncation ~ (h inv_s)^2).
  c.step_double = {1e-5 / inv_s, 1e-5 / inv_s, 1e-6, 1e-6 * inv_s};
  // Float: sdf moves 0.05/inv_s (s * step = 0.05: truncation ~4e-4 relative, rounding ~1e-6); cos
  // moves at most 0.02 (the kinks are 0.2 away); rgb is linear; inv_s moves by 1e-3 of itself.
  c.step_float = {0.05 / inv_s, std::min(0.02, 1.5 / inv_s), 1e-2, 1e-3 * inv_s};
  return c;
}

class VolumeRenderCheck : public gradcheck::WithReference<VolumeRenderCheck> {
 public:
  std::string name() const override { return "neus/volume_render"; }
  std::vector<std::string> input_names() const override { return {"sdf", "cos", "rgb", "inv_s"}; }
  std::vector<std::string> output_names() const override { return {"colour", "opacity"}; }

  std::vector<Case> cases() const override {
    return {make_case("rays5_s16_inv_s32", 5, 16, 11, 32.0, 0.0), make_case("anneal_half_4x16", 4, 16, 12, 48.0, 0.5),
            make_case("sharp_inv_s1e3_3x16", 3, 16, 13, 1e3, 1.0)};
  }

  template <class T>
  static std::vector<T> dist_as(const Params& p) {
    const auto d = dists(p);
    return {d.begin(), d.end()};
  }

  template <class T>
  Arrays<T> forward(const Params& p, const Arrays<T>& in) const {
    const auto d = dist_as<T>(p);
    const VolumeRenderInputs<T> v{in[0], in[1], d, in[2], in[3][0]};
    auto out = volume_render_forward_ref<T>(rays_of(p), samples_of(p), v, p.at("cos_anneal"));
    return {std::move(out.colour), std::move(out.opacity)};
  }

  template <class T>
  Arrays<T> backward(const Params& p, const Arrays<T>& in, const Arrays<T>& g) const {
    const auto d = dist_as<T>(p);
    const VolumeRenderInputs<T> v{in[0], in[1], d, in[2], in[3][0]};
    auto r = volume_render_backward_ref<T>(rays_of(p), samples_of(p), v, p.at("cos_anneal"), g[0], g[1]);
    return {std::move(r.sdf), std::move(r.cos), std::move(r.rgb), {r.inv_s}};
  }

  Arrays<float> device_forward(gpu::Context& ctx, const Params& p, const Arrays<float>& in) const override {
    const auto d = dist_as<float>(p);
    VolumeRenderParams params;
    params.cos_anneal = float(p.at("cos_anneal"));
    auto out = volume_render(ctx, samples_of(p), {in[0], in[1], d, in[2], in[3][0]}, params);
    return {std::move(out.colour), std::move(out.opacity)};
  }

  Arrays<float> device_backward(gpu::Context& ctx, const Params& p, const Arrays<float>& in,
                                const Arrays<float>& g) const override {
    const auto d = dist_as<float>(p);
    VolumeRenderParams params;
    params.cos_anneal = float(p.at("cos_anneal"));
    auto r = volume_render_with_gradients(ctx, samples_of(p), {in[0], in[1], d, in[2], in[3][0]}, params, g[0], g[1]);
    return {std::move(r.grads.sdf), std::move(r.grads.cos), std::move(r.grads.rgb), {r.grads.inv_s}};
  }
};

}  // namespace

std::unique_ptr<gradcheck::DifferentiableKernel> make_volume_render_check() {
  return std::make_unique<VolumeRenderCheck>();
}

}  // namespace nf::neus
