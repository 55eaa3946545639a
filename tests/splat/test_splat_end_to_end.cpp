// End to end: the paper's image losses (silhouette L1 and orientation with rendered confidence) of
// rasterised strands, differentiated on the GPU all the way to the strand points, against central
// finite differences of the CPU references in double, on a tiny scene (3 strands, 32x32 image).
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "engine/splat/image_losses.hpp"
#include "engine/splat/image_losses_ref.hpp"
#include "engine/splat/rasterizer.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::splat;

namespace {

constexpr std::uint32_t kW = 32, kH = 32, kStrands = 3, kL = 6;
constexpr double kSilWeight = 0.1, kDirWeight = 1.0;

RasterCamera camera() {
  RasterCamera c;
  c.width = kW, c.height = kH, c.fx = c.fy = 40, c.cx = 16, c.cy = 16;
  c.world_to_camera[11] = -2;
  c.near = 0.1, c.far = 10;
  return c;
}

RasterParams params() {
  RasterParams p;
  p.gaussian = {0.5, 0.04};
  return p;
}

struct Targets {
  std::vector<double> mask, weight, angle, confidence;
};

Targets targets() {
  Targets t;
  for (std::uint32_t y = 0; y < kH; ++y)
    for (std::uint32_t x = 0; x < kW; ++x) {
      const double dx = x - 15.5, dy = y - 14.0;
      t.mask.push_back(dx * dx + 1.5 * dy * dy < 90 ? 1.0 : 0.0);
      t.weight.push_back(x < 28 ? 1.0 : 0.0);  // a bald strip on the right
      t.angle.push_back(std::fmod(0.4 + 0.03 * x + 0.02 * y, 3.14159265358979));
      t.confidence.push_back(0.5 + 0.5 * std::sin(0.2 * x) * std::sin(0.2 * x));
    }
  return t;
}

template <class T>
std::vector<T> cast(const std::vector<double>& v) {
  return std::vector<T>(v.begin(), v.end());
}

// The weighted loss of the reference pipeline in double.
double reference_loss(const std::vector<double>& points, const std::vector<double>& conf, const Targets& t) {
  std::vector<double> image;
  rasterize_ref(points, conf, kStrands, kL, camera(), params(), {}, image);
  const std::size_t n = std::size_t(kW) * kH;
  const ImageLossInputs<double> in{std::span(image).subspan(0, n), std::span(image).subspan(n, 2 * n), std::span(image).subspan(3 * n, n)};
  const ImageLossTargets<double> tg{t.mask, t.weight, t.angle, t.confidence};
  const auto v = image_losses_forward_ref<double>(n, in, tg, ImageLossParams{});
  return kSilWeight * v.silhouette + kDirWeight * v.orientation;
}

}  // namespace

TEST_CASE("image losses through the rasteriser: GPU gradients of the strand points match finite differences") {
  gpu::Context& ctx = test::context();
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> points, conf;
  for (std::uint32_t s = 0; s < kStrands; ++s) {
    double p[3] = {0.25 * u(rng), 0.25 * u(rng), 0.1 * u(rng)};
    double d[3] = {u(rng), u(rng), 0.2 * u(rng)};
    for (std::uint32_t l = 0; l < kL; ++l) {
      points.insert(points.end(), p, p + 3);
      for (int k = 0; k < 3; ++k) d[k] += 0.3 * u(rng), p[k] += 0.06 * d[k];
    }
    for (std::uint32_t l = 0; l + 1 < kL; ++l) conf.push_back(0.5 + 0.4 * u(rng));
  }
  const Targets t = targets();
  const std::size_t n = std::size_t(kW) * kH;

  // GPU: rasterise, losses and their adjoint, then the rasteriser's adjoint.
  const StrandShape shape{kStrands, kL};
  const std::vector<float> pts_f = cast<float>(points), conf_f = cast<float>(conf);
  const std::vector<float> image = rasterize(ctx, shape, pts_f, conf_f, camera(), params());
  const std::vector<float> mask = cast<float>(t.mask), weight = cast<float>(t.weight), angle = cast<float>(t.angle),
                           confidence = cast<float>(t.confidence);
  const ImageLossInputs<float> in{std::span(image).subspan(0, n), std::span(image).subspan(n, 2 * n), std::span(image).subspan(3 * n, n)};
  const ImageLossResult losses = image_losses_with_gradients(ctx, {kW, kH}, in, {mask, weight, angle, confidence}, float(kSilWeight),
                                                             float(kDirWeight));
  const double gpu_loss = kSilWeight * losses.values.silhouette + kDirWeight * losses.values.orientation;
  CHECK(gpu_loss == doctest::Approx(reference_loss(points, conf, t)).epsilon(1e-4));
  CHECK(losses.values.silhouette > 0.01);   // both terms are active in this scene
  CHECK(losses.values.orientation > 0.01);
  std::vector<float> grad_image(n * kChannels, 0.0f);
  for (std::size_t i = 0; i < n; ++i) {
    grad_image[i] = losses.grads.alpha[i];
    grad_image[n + i] = losses.grads.orientation[i];
    grad_image[2 * n + i] = losses.grads.orientation[n + i];
    grad_image[3 * n + i] = losses.grads.tau[i];
  }
  const RasterGradients grads = rasterize_backward(ctx, shape, pts_f, conf_f, camera(), params(), {}, grad_image);

  // Reference: central differences in double.
  const double h = 1e-6;
  double worst = 0, largest = 0;
  std::vector<double> fd(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::vector<double> a = points, b = points;
    a[i] += h, b[i] -= h;
    fd[i] = (reference_loss(a, conf, t) - reference_loss(b, conf, t)) / (2 * h);
    largest = std::max(largest, std::fabs(fd[i]));
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    REQUIRE(std::isfinite(grads.points[i]));
    worst = std::max(worst, std::fabs(grads.points[i] - fd[i]));
  }
  INFO("max |gpu - fd| = " << worst << ", largest |fd| = " << largest);
  CHECK(largest > 1e-3);
  CHECK(worst <= 1e-2 * largest);
  // And the confidence: it reaches the loss through the rendered tau.
  double worst_conf = 0, largest_conf = 0;
  for (std::size_t i = 0; i < conf.size(); ++i) {
    std::vector<double> a = conf, b = conf;
    a[i] += h, b[i] -= h;
    const double d = (reference_loss(points, a, t) - reference_loss(points, b, t)) / (2 * h);
    largest_conf = std::max(largest_conf, std::fabs(d));
    worst_conf = std::max(worst_conf, std::fabs(grads.confidence[i] - d));
  }
  CHECK(largest_conf > 1e-4);
  CHECK(worst_conf <= 1e-2 * largest_conf);
}
