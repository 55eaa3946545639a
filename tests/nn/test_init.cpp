// Initialisation schemes: the statistics they promise, zero padding, and the geometric init
// starting as a sphere's SDF.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "engine/core/error.hpp"
#include "engine/nn/init.hpp"
#include "engine/nn/mlp_ref.hpp"

using namespace nf;
using namespace nf::nn;

namespace {

MlpConfig sdf_net(std::uint32_t in) {
  MlpConfig c;
  c.input_dim = in;
  c.hidden = {256, 256, 256, 256};
  c.output_dim = 1;
  c.hidden_activation = {Activation::Softplus, 100.f, 30.f};
  return c;
}

bool padding_is_zero(const MlpConfig& c, const std::vector<float>& p) {
  std::vector<bool> used(p.size(), false);
  for (const LayerShape& l : c.layers()) {
    for (std::uint32_t o = 0; o < l.out; ++o) {
      for (std::uint32_t k = 0; k < l.in; ++k) used[l.weight_offset + std::uint64_t(o) * l.in_stride + k] = true;
      used[l.bias_offset + o] = true;
    }
  }
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!used[i] && p[i] != 0.f) return false;
  return true;
}

}  // namespace

TEST_CASE("geometric init starts as the SDF of a sphere") {
  const MlpConfig c = sdf_net(7);  // xyz plus 4 encoding features that start silent
  InitOptions o;
  o.scheme = InitScheme::Geometric;
  o.radius = 0.5f;
  const auto params = initial_parameters(c, o);
  CHECK(padding_is_zero(c, params));
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::uint32_t batch = 2000, stride = pad4(7);
  std::vector<double> x(std::size_t(batch) * stride, 0.0), radius(batch);
  for (std::uint32_t s = 0; s < batch; ++s) {
    double r2 = 0;
    for (int a = 0; a < 7; ++a) x[s * stride + a] = u(rng);
    for (int a = 0; a < 3; ++a) r2 += x[s * stride + a] * x[s * stride + a];
    radius[s] = std::sqrt(r2);
  }
  const std::vector<double> pd(params.begin(), params.end());
  const auto out = mlp_forward_ref<double>(c, pd, x, batch).y.back();
  // Least-squares line f = a |x| + b: a sphere of radius -b/a, and how well the line explains f.
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  for (std::uint32_t s = 0; s < batch; ++s) {
    const double xr = radius[s], y = out[s * 4];
    sx += xr, sy += y, sxx += xr * xr, sxy += xr * y, syy += y * y;
  }
  const double a = (batch * sxy - sx * sy) / (batch * sxx - sx * sx), b = (sy - a * sx) / batch;
  const double r = (batch * sxy - sx * sy) / std::sqrt((batch * sxx - sx * sx) * (batch * syy - sy * sy));
  MESSAGE("geometric init: f = " << a << " |x| + " << b << ", correlation " << r);
  // Finite width makes it a noisy sphere: measured slope 0.92, radius 0.475, correlation 0.90.
  CHECK(r > 0.85);
  CHECK(a == doctest::Approx(1.0).epsilon(0.3));
  CHECK(-b / a == doctest::Approx(0.5).epsilon(0.2));
  // Inside negative, outside positive, on average.
  double inside = 0, outside = 0;
  int n_in = 0, n_out = 0;
  for (std::uint32_t s = 0; s < batch; ++s) {
    if (radius[s] < 0.3) inside += out[s * 4], ++n_in;
    if (radius[s] > 0.8) outside += out[s * 4], ++n_out;
  }
  CHECK(inside / n_in < 0);
  CHECK(outside / n_out > 0);
}

TEST_CASE("Kaiming and SIREN inits draw from the promised ranges, deterministically") {
  MlpConfig c;
  c.input_dim = 63;
  c.hidden = {256, 256};
  c.output_dim = 129;
  InitOptions o;
  o.scheme = InitScheme::KaimingUniform;
  const auto a = initial_parameters(c, o), b = initial_parameters(c, o);
  CHECK(a == b);
  CHECK(padding_is_zero(c, a));
  const LayerShape l1 = c.layers()[1];
  double sum2 = 0, most = 0;
  for (std::uint32_t i = 0; i < l1.out; ++i)
    for (std::uint32_t k = 0; k < l1.in; ++k) {
      const double w = a[l1.weight_offset + std::uint64_t(i) * l1.in_stride + k];
      sum2 += w * w;
      most = std::max(most, std::fabs(w));
    }
  CHECK(most <= 1.0 / 16.0);                                            // 1/sqrt(256)
  CHECK(sum2 / (256.0 * 256.0) == doctest::Approx(1.0 / (3 * 256.0)).epsilon(0.05));  // uniform variance

  o.scheme = InitScheme::KaimingNormal;
  const auto n = initial_parameters(c, o);
  sum2 = 0;
  for (std::uint32_t i = 0; i < l1.out; ++i)
    for (std::uint32_t k = 0; k < l1.in; ++k) sum2 += std::pow(n[l1.weight_offset + std::uint64_t(i) * l1.in_stride + k], 2);
  CHECK(sum2 / (256.0 * 256.0) == doctest::Approx(2.0 / 256).epsilon(0.05));

  c.hidden_activation = {Activation::Sine, 100.f, 30.f};
  o.scheme = InitScheme::Siren;
  const auto s = initial_parameters(c, o);
  const LayerShape l0 = c.layers()[0];
  for (std::uint32_t k = 0; k < l0.in; ++k) CHECK(std::fabs(s[l0.weight_offset + k]) <= 1.0 / 63);
  for (std::uint32_t k = 0; k < l1.in; ++k) CHECK(std::fabs(s[l1.weight_offset + k]) <= std::sqrt(6.0 / 256) / 30);
}

TEST_CASE("geometric init rejects more position columns than inputs") {
  InitOptions o;
  o.scheme = InitScheme::Geometric;
  o.position_columns = 5;
  CHECK_THROWS_AS(initial_parameters(sdf_net(3), o), InputError);
}
