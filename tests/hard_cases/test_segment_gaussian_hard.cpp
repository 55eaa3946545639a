// Hard cases of DESIGN §4 for the segment-to-Gaussian kernel: outputs and gradients stay finite
// and sensible on degenerate strands; bad input is rejected with an error naming it.
#include <doctest/doctest.h>

#include <cmath>

#include "engine/core/error.hpp"
#include "engine/splat/segment_gaussian.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::splat;

namespace {

bool finite(const std::vector<float>& v) {
  return std::all_of(v.begin(), v.end(), [](float x) { return std::isfinite(x); });
}

}  // namespace

TEST_CASE("zero-length strands become isotropic Gaussians of the strand width, with finite gradients") {
  auto& ctx = test::context();
  const StrandShape shape{2, 4};
  std::vector<float> pts(shape.points() * 3, 0.25f);  // every point identical
  SegmentGaussianParams params;
  params.width = 0.01;
  const auto g = segment_gaussians(ctx, shape, params, pts);
  REQUIRE(finite(g.means));
  REQUIRE(finite(g.covariances));
  for (std::uint64_t s = 0; s < shape.segments(); ++s) {
    const float* c = &g.covariances[s * 6];
    CHECK(c[0] == doctest::Approx(1e-4));
    CHECK(c[3] == doctest::Approx(1e-4));
    CHECK(c[5] == doctest::Approx(1e-4));
    CHECK(c[1] == 0.f);
    // d = 0: C = eps^2 I exactly (the d d^T term vanishes), checked relative to eps^2 = 1e-4 (the
    // Approx above allows ~1e-5 absolute); the mean is the common point.
    for (int k : {0, 3, 5}) CHECK(c[k] / 1e-4 == doctest::Approx(1.0).epsilon(1e-6));
    CHECK(c[2] == 0.f);
    CHECK(c[4] == 0.f);
    for (int j = 0; j < 3; ++j) CHECK(g.means[s * 3 + j] == doctest::Approx(0.25).epsilon(1e-7));
  }
  const std::vector<float> gm(shape.segments() * 3, 1.f), gc(shape.segments() * 6, 1.f);
  const auto grad = segment_gaussians_backward(ctx, shape, params, pts, gm, gc);
  CHECK(finite(grad));
  // d = 0 makes dL/dd = 2 a H d + (...) d = 0, so only the means pull: a point gets 1/2 of dL/dmean = 1
  // from each segment it bounds, i.e. 1/2 at a strand's two ends and 1 inside.
  REQUIRE(grad.size() == shape.points() * 3);
  for (std::uint64_t i = 0; i < shape.points(); ++i) {
    const std::uint32_t l = std::uint32_t(i % shape.points_per_strand);
    const double want = (l == 0 || l + 1 == shape.points_per_strand) ? 0.5 : 1.0;
    for (int j = 0; j < 3; ++j) CHECK(grad[i * 3 + j] == doctest::Approx(want).epsilon(1e-6));
  }
}

TEST_CASE("covariances stay symmetric positive definite from 1e-6 to 1e3 scene units") {
  auto& ctx = test::context();
  for (double scale : {1e-6, 1e-3, 1.0, 1e3}) {
    CAPTURE(scale);
    const StrandShape shape{1, 5};
    std::vector<float> pts;
    for (int l = 0; l < 5; ++l) {
      const double p[3] = {0.1 * l * scale, 0.03 * l * l * scale, (l == 2 ? 0.2 : 0.1 * l) * scale};
      pts.insert(pts.end(), p, p + 3);
    }
    SegmentGaussianParams params;
    params.width = 0.0025 * scale;
    const auto g = segment_gaussians(ctx, shape, params, pts);
    REQUIRE(finite(g.covariances));
    for (std::uint64_t s = 0; s < shape.segments(); ++s) {
      const float* c = &g.covariances[s * 6];
      // Leading principal minors of [[xx xy xz][xy yy yz][xz yz zz]] are positive.
      const double m1 = c[0], m2 = double(c[0]) * c[3] - double(c[1]) * c[1];
      const double m3 = c[0] * (double(c[3]) * c[5] - double(c[4]) * c[4]) - c[1] * (double(c[1]) * c[5] - double(c[4]) * c[2]) +
                        c[2] * (double(c[1]) * c[4] - double(c[3]) * c[2]);
      CHECK(m1 > 0);
      CHECK(m2 > 0);
      CHECK(m3 > 0);
      // Across the segment the variance is eps^2; along it, (k|d|)^2 (+ a guard term ~eps^2 delta^2/|d|^2).
      const float* p0 = &pts[s * 3];
      const double d[3] = {double(p0[3]) - p0[0], double(p0[4]) - p0[1], double(p0[5]) - p0[2]};
      const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      const double u[3] = {d[0] / len, d[1] / len, d[2] / len};
      double v[3] = {-u[1], u[0], 0.0};  // perpendicular to u
      const double vn = std::sqrt(v[0] * v[0] + v[1] * v[1]);
      for (double& x : v) x /= vn;
      const auto quad = [&](const double* w) {
        const double cw[3] = {c[0] * w[0] + c[1] * w[1] + c[2] * w[2], c[1] * w[0] + c[3] * w[1] + c[4] * w[2],
                              c[2] * w[0] + c[4] * w[1] + c[5] * w[2]};
        return w[0] * cw[0] + w[1] * cw[1] + w[2] * cw[2];
      };
      const double eps2 = params.width * params.width;
      CHECK(quad(v) == doctest::Approx(eps2).epsilon(1e-3));
      CHECK(quad(u) == doctest::Approx(0.25 * len * len).epsilon(1e-4));
    }
  }
}

TEST_CASE("NaN and Inf in strand points are rejected with an error naming the input and element") {
  auto& ctx = test::context();
  const StrandShape shape{1, 3};
  std::vector<float> pts(9, 0.5f);
  pts[4] = NAN;
  CHECK_THROWS_WITH_AS(segment_gaussians(ctx, shape, {}, pts), doctest::Contains("strand points: element 4"),
                       InputError);
  pts[4] = INFINITY;
  CHECK_THROWS_WITH_AS(segment_gaussians(ctx, shape, {}, pts), doctest::Contains("strand points: element 4"),
                       InputError);
  pts[4] = 0.f;
  std::vector<float> gm(6, 0.f), gc(12, 0.f);
  gc[7] = -INFINITY;
  CHECK_THROWS_WITH_AS(segment_gaussians_backward(ctx, shape, {}, pts, gm, gc),
                       doctest::Contains("gradient of segment covariances: element 7"), InputError);
}

TEST_CASE("inconsistent sizes and parameters are rejected with the field named") {
  auto& ctx = test::context();
  std::vector<float> pts(9, 0.f);
  CHECK_THROWS_WITH_AS(segment_gaussians(ctx, {1, 1}, {}, std::vector<float>(3, 0.f)),
                       doctest::Contains("points_per_strand"), InputError);
  CHECK_THROWS_WITH_AS(segment_gaussians(ctx, {2, 3}, {}, pts), doctest::Contains("18 expected"), InputError);
  SegmentGaussianParams bad;
  bad.width = 0;
  CHECK_THROWS_WITH_AS(segment_gaussians(ctx, {1, 3}, bad, pts), doctest::Contains("width"), InputError);
  bad = {};
  bad.length_scale = NAN;
  CHECK_THROWS_WITH_AS(segment_gaussians(ctx, {1, 3}, bad, pts), doctest::Contains("length_scale"), InputError);
}

TEST_CASE("empty strand sets give empty outputs") {
  auto& ctx = test::context();
  const auto g = segment_gaussians(ctx, {0, 100}, {}, std::vector<float>());
  CHECK(g.means.empty());
  CHECK(g.covariances.empty());
}

TEST_CASE("many strands are processed in binding-sized chunks with the same result as one pass") {
  auto& ctx = test::context();
  // 2^17 strands x 100 points: 150 MiB of points, more than lavapipe's 128 MiB binding range.
  const StrandShape shape{1u << 17, 100};
  std::vector<float> pts(shape.points() * 3);
  for (std::size_t i = 0; i < pts.size(); ++i) pts[i] = float((i * 7919) % 1000) * 1e-3f;
  const auto g = segment_gaussians(ctx, shape, {}, pts);
  // Spot-check segments near the start, the chunk boundary region and the end against the reference.
  std::vector<float> ref_means, ref_covs;
  for (std::uint32_t strand : {0u, (1u << 16) + 17, (1u << 17) - 1}) {
    const std::vector<float> one(pts.begin() + std::ptrdiff_t(strand) * 300, pts.begin() + std::ptrdiff_t(strand + 1) * 300);
    segment_gaussian_forward_ref(one, 1, 100, {}, ref_means, ref_covs);
    for (std::size_t k = 0; k < ref_covs.size(); ++k)
      CHECK(g.covariances[std::size_t(strand) * 99 * 6 + k] == doctest::Approx(ref_covs[k]).epsilon(1e-5));
    for (std::size_t k = 0; k < ref_means.size(); ++k)
      CHECK(g.means[std::size_t(strand) * 99 * 3 + k] == doctest::Approx(ref_means[k]).epsilon(1e-6));
  }
}
