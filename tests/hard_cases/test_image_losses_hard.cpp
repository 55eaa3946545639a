// Hard cases for the image-space losses of strand splatting (silhouette and orientation): degenerate
// images and inputs give the expected values with finite gradients, the GPU matches the double CPU
// reference on a 1920x1080 view, planes bind at any offset, and bad input is rejected by name.
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <random>
#include <tuple>

#include "engine/core/error.hpp"
#include "engine/splat/image_losses.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::splat;

namespace {

constexpr double kPi = 3.14159265358979323846;

bool finite(const std::vector<float>& v) {
  return std::all_of(v.begin(), v.end(), [](float x) { return std::isfinite(x); });
}
bool all_zero(const std::vector<float>& v) {
  return std::all_of(v.begin(), v.end(), [](float x) { return x == 0.f; });
}

// One view's arrays; random unless a test overwrites them.
struct View {
  ImageSize size;
  std::vector<float> alpha, orientation, tau, mask, weight, angle, confidence;
  View(std::uint32_t w, std::uint32_t h, unsigned seed) : size{w, h} {
    const std::uint64_t n = size.pixels();
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (std::uint64_t i = 0; i < n; ++i) {
      alpha.push_back(u(rng));
      tau.push_back(0.01f + u(rng));
      mask.push_back(u(rng) < 0.5f ? 0.f : 1.f);
      weight.push_back(u(rng) < 0.2f ? 0.f : u(rng));
      angle.push_back(float(kPi) * u(rng) * 0.99999f);
      confidence.push_back(2.f * u(rng));
    }
    orientation.resize(2 * n);
    for (std::uint64_t i = 0; i < n; ++i) {
      const float theta = float(kPi) * u(rng), m = u(rng);
      orientation[i] = m * std::cos(2 * theta);
      orientation[n + i] = m * std::sin(2 * theta);
    }
  }
  ImageLossInputs<float> inputs() const { return {alpha, orientation, tau}; }
  ImageLossTargets<float> targets() const { return {mask, weight, angle, confidence}; }
};

struct Reference {
  ImageLossValues<double> values;
  ImageLossGradients<double> grads;
};
std::vector<double> widen(const std::vector<float>& v) { return {v.begin(), v.end()}; }
Reference reference(const View& v, double gs, double gd) {
  const auto a = widen(v.alpha), o = widen(v.orientation), t = widen(v.tau), m = widen(v.mask), w = widen(v.weight),
             g = widen(v.angle), c = widen(v.confidence);
  const ImageLossInputs<double> in{a, o, t};
  const ImageLossTargets<double> tg{m, w, g, c};
  const ImageLossParams p;
  Reference r;
  r.values = image_losses_forward_ref<double>(v.size.pixels(), in, tg, p);
  r.grads = image_losses_backward_ref<double>(v.size.pixels(), in, tg, p, r.values, gs, gd);
  return r;
}

// max |gpu - ref| / max |ref| over the pixels `use` accepts.
template <class Use>
double rel_error(const std::vector<float>& gpu, const std::vector<double>& ref, Use use) {
  double scale = 0, err = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) scale = std::max(scale, std::fabs(ref[i]));
  for (std::size_t i = 0; i < ref.size(); ++i)
    if (use(i)) err = std::max(err, std::fabs(double(gpu[i]) - ref[i]));
  return scale > 0 ? err / scale : err;
}
double rel_error(const std::vector<float>& gpu, const std::vector<double>& ref) {
  return rel_error(gpu, ref, [](std::size_t) { return true; });
}

}  // namespace

TEST_CASE("a 1x1 image gives the hand-computed losses and gradients") {
  auto& ctx = test::context();
  View v(1, 1, 1);
  const double theta = 0.4, beta_hat = 0.1, tau = 0.5, m = 0.7;
  v.alpha = {0.3f};
  v.mask = {1.f};
  v.weight = {0.5f};
  v.angle = {float(beta_hat)};
  v.confidence = {2.f};
  v.tau = {float(tau)};
  v.orientation = {float(m * std::cos(2 * theta)), float(m * std::sin(2 * theta))};
  const auto r = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 0.1f, 1000.f);
  CHECK(r.values.silhouette == doctest::Approx(0.7).epsilon(1e-6));
  CHECK(r.values.orientation == doctest::Approx(tau * (theta - beta_hat) - std::log(tau)).epsilon(1e-5));
  CHECK(r.values.silhouette_norm == doctest::Approx(0.5));
  CHECK(r.values.orientation_norm == doctest::Approx(1.0));
  CHECK(r.grads.alpha[0] == doctest::Approx(-0.1 * 0.5 / 0.5));
  CHECK(r.grads.tau[0] == doctest::Approx(1000.0 * ((theta - beta_hat) - 1 / tau)).epsilon(1e-5));
  // dbeta/do = (-o_y, o_x) / (2 |o|^2), slope +1, w / N_dir = 1.
  const double ox = m * std::cos(2 * theta), oy = m * std::sin(2 * theta);
  CHECK(r.grads.orientation[0] == doctest::Approx(1000.0 * tau * -oy / (2 * m * m)).epsilon(1e-5));
  CHECK(r.grads.orientation[1] == doctest::Approx(1000.0 * tau * ox / (2 * m * m)).epsilon(1e-5));
}

TEST_CASE("an empty mask and a full mask give the silhouette loss and gradient signs expected") {
  auto& ctx = test::context();
  for (const float target : {0.f, 1.f}) {
    CAPTURE(target);
    View v(37, 23, 2);
    std::fill(v.mask.begin(), v.mask.end(), target);
    for (float& a : v.alpha) a = std::clamp(a, 0.01f, 0.99f);  // never exactly on the mask
    const auto r = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 1.f, 1.f);
    double num = 0, den = 0;
    for (std::size_t i = 0; i < v.alpha.size(); ++i) {
      num += v.weight[i] * std::fabs(v.alpha[i] - target);
      den += v.weight[i];
    }
    CHECK(r.values.silhouette == doctest::Approx(num / den).epsilon(1e-5));
    REQUIRE(finite(r.grads.alpha));
    for (std::size_t i = 0; i < v.alpha.size(); ++i) {
      if (v.weight[i] == 0.f) {
        CHECK(r.grads.alpha[i] == 0.f);
      } else if (target == 0.f) {
        CHECK(r.grads.alpha[i] > 0.f);  // more hair where the photo has none raises the loss
      } else {
        CHECK(r.grads.alpha[i] < 0.f);
      }
      // dL_sil/dalpha = weight sign(alpha - mask) / N_sil, N_sil = sum of weights (upstream factor 1).
      CHECK(r.grads.alpha[i] * den == doctest::Approx((target == 0.f ? 1.0 : -1.0) * v.weight[i]).epsilon(1e-5));
    }
  }
  // A full mask under a full prediction: |alpha - mask| = 0 everywhere, so no loss, and the kink's
  // subgradient sign(0) = 0 gives no gradient.
  View v(37, 23, 2);
  std::fill(v.mask.begin(), v.mask.end(), 1.f);
  std::fill(v.alpha.begin(), v.alpha.end(), 1.f);
  const auto r = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 1.f, 1.f);
  CHECK(r.values.silhouette == 0.f);
  CHECK(all_zero(r.grads.alpha));
}

TEST_CASE("weight zero everywhere gives zero losses and zero gradients, no NaN") {
  auto& ctx = test::context();
  View v(19, 11, 3);
  std::fill(v.weight.begin(), v.weight.end(), 0.f);
  const auto r = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 0.1f, 1000.f);
  CHECK(r.values.silhouette == 0.f);
  CHECK(r.values.orientation == 0.f);
  CHECK(r.values.silhouette_norm == doctest::Approx(1e-6));  // the normaliser guard
  // Both normalisers are the guard itself (relative: Approx's default allows ~1e-5 absolute).
  CHECK(r.values.silhouette_norm / 1e-6 == doctest::Approx(1.0).epsilon(1e-6));
  CHECK(r.values.orientation_norm / 1e-6 == doctest::Approx(1.0).epsilon(1e-6));
  CHECK(all_zero(r.grads.alpha));
  CHECK(all_zero(r.grads.orientation));
  CHECK(all_zero(r.grads.tau));
}

TEST_CASE("a rendered orientation of exactly zero has no orientation term and zero gradients") {
  auto& ctx = test::context();
  View v(13, 7, 4);
  std::fill(v.orientation.begin(), v.orientation.end(), 0.f);
  const auto r = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 0.1f, 1000.f);
  CHECK(r.values.orientation == 0.f);
  CHECK(r.values.silhouette > 0.f);
  CHECK(all_zero(r.grads.orientation));
  CHECK(all_zero(r.grads.tau));
  CHECK(finite(r.grads.alpha));
  // The silhouette term does not see the orientation: as the reference has it.
  const auto ref = reference(v, 0.1, 1000.0);
  CHECK(r.values.silhouette == doctest::Approx(ref.values.silhouette).epsilon(1e-5));
  CHECK(rel_error(r.grads.alpha, ref.grads.alpha) < 1e-5);
  // Just above the gate (|o| = 2e-6) the gradient is large, ~1/|o|, but finite.
  std::fill(v.orientation.begin(), v.orientation.begin() + v.size.pixels(), 2e-6f);
  const auto tiny = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 0.1f, 1000.f);
  CHECK(finite(tiny.grads.orientation));
  CHECK(finite(tiny.grads.tau));
  CHECK(std::isfinite(tiny.values.orientation));
  CHECK(tiny.values.orientation > 0.f);
  // o = (2e-6, 0): beta = 0 exactly, and dL/do = a w t s (0, 2e-6) / (2 (2e-6)^2 N_dir) is well
  // conditioned however large: the reference gives every value.
  const auto tiny_ref = reference(v, 0.1, 1000.0);
  CHECK(tiny.values.orientation == doctest::Approx(tiny_ref.values.orientation).epsilon(1e-5));
  CHECK(rel_error(tiny.grads.orientation, tiny_ref.grads.orientation) < 1e-4);
  CHECK(rel_error(tiny.grads.tau, tiny_ref.grads.tau) < 1e-5);
}

TEST_CASE("tau = 0 uses the floor: finite loss, zero tau gradient, finite orientation gradient") {
  auto& ctx = test::context();
  View v(17, 9, 5);
  std::fill(v.tau.begin(), v.tau.end(), 0.f);
  const auto r = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 0.1f, 1000.f);
  const auto ref = reference(v, 0.1, 1000.0);
  CHECK(std::isfinite(r.values.orientation));
  CHECK(r.values.orientation == doctest::Approx(ref.values.orientation).epsilon(1e-5));
  CHECK(r.values.orientation > 9.f * 0.5f);  // about -log(1e-4) = 9.2 per active pixel, some inactive
  CHECK(all_zero(r.grads.tau));
  CHECK(finite(r.grads.orientation));
  CHECK(rel_error(r.grads.orientation, ref.grads.orientation) < 1e-4);
}

TEST_CASE("Gabor angles exactly 0 and near pi fold onto the same difference") {
  auto& ctx = test::context();
  // Rendered directions 0.3 and -0.2 rad against Gabor angles 0, pi - 1e-6 and float(pi).
  const float angles[] = {0.f, float(kPi - 1e-6), float(kPi)};
  const double thetas[] = {0.3, -0.2};
  for (const float gabor : angles)
    for (const double theta : thetas) {
      CAPTURE(gabor);
      CAPTURE(theta);
      View v(1, 1, 6);
      v.alpha = {0.5f};
      v.mask = {1.f};
      v.weight = {1.f};
      v.confidence = {1.f};
      v.tau = {1.f};
      v.angle = {gabor};
      v.orientation = {float(std::cos(2 * theta)), float(std::sin(2 * theta))};
      const auto r = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 0.f, 1.f);
      const double dmin = std::min(std::fabs(std::fmod(theta - double(gabor) + 2 * kPi, kPi)),
                                   kPi - std::fabs(std::fmod(theta - double(gabor) + 2 * kPi, kPi)));
      CHECK(r.values.orientation == doctest::Approx(dmin).epsilon(1e-5));
      CHECK(dmin == doctest::Approx(std::fabs(theta)).epsilon(1e-5));
      // The loss grows as the rendered angle moves away from the Gabor angle: d L / d theta = sign(theta).
      const double dtheta = -2 * std::sin(2 * theta) * r.grads.orientation[0] + 2 * std::cos(2 * theta) * r.grads.orientation[1];
      CHECK(dtheta == doctest::Approx(theta > 0 ? 1.0 : -1.0).epsilon(1e-5));
      CHECK(r.grads.tau[0] == doctest::Approx(dmin - 1.0).epsilon(1e-5));
    }
}

TEST_CASE("odd sizes and many workgroups match the reference") {
  auto& ctx = test::context();
  for (const auto& [w, h] : {std::pair{257u, 3u}, std::pair{1u, 1001u}, std::pair{333u, 77u}}) {
    CAPTURE(w);
    CAPTURE(h);
    View v(w, h, w + h);
    const auto r = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 0.1f, 1000.f);
    const auto ref = reference(v, 0.1, 1000.0);
    CHECK(r.values.silhouette == doctest::Approx(ref.values.silhouette).epsilon(1e-5));
    CHECK(r.values.orientation == doctest::Approx(ref.values.orientation).epsilon(1e-5));
    CHECK(rel_error(r.grads.alpha, ref.grads.alpha) < 1e-5);
    CHECK(rel_error(r.grads.tau, ref.grads.tau) < 1e-5);
    CHECK(rel_error(r.grads.orientation, ref.grads.orientation) < 1e-4);
  }
}

TEST_CASE("images split over many dispatches (chunks) give the same losses and gradients") {
  auto& ctx = test::context();
  for (const auto& [w, h, chunk] : {std::tuple{333u, 77u, 1000u}, std::tuple{19u, 11u, 7u}}) {
    CAPTURE(chunk);
    View v(w, h, 10 + chunk);
    const auto whole = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 0.1f, 1000.f);
    ImageLossParams p;
    p.chunk_pixels = chunk;
    const auto split = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 0.1f, 1000.f, p);
    CHECK(split.values.silhouette == doctest::Approx(whole.values.silhouette).epsilon(1e-6));
    CHECK(split.values.orientation == doctest::Approx(whole.values.orientation).epsilon(1e-6));
    CHECK(split.values.silhouette_norm == doctest::Approx(whole.values.silhouette_norm).epsilon(1e-6));
    CHECK(split.values.orientation_norm == doctest::Approx(whole.values.orientation_norm).epsilon(1e-6));
    CHECK(rel_error(split.grads.alpha, widen(whole.grads.alpha)) < 1e-6);
    CHECK(rel_error(split.grads.orientation, widen(whole.grads.orientation)) < 1e-6);
    CHECK(rel_error(split.grads.tau, widen(whole.grads.tau)) < 1e-6);
  }
}

TEST_CASE("planes of a rasteriser-style image bind at any offset") {
  auto& ctx = test::context();
  // 5 planes (alpha, o_x, o_y, tau, depth) of 7x5 = 35 pixels: planes 1-4 start off the alignment.
  View v(7, 5, 7);
  const std::uint64_t n = v.size.pixels();
  std::vector<float> image(5 * n, 0.f), targets(4 * n + 3, 0.f);
  std::copy(v.alpha.begin(), v.alpha.end(), image.begin());
  std::copy(v.orientation.begin(), v.orientation.end(), image.begin() + n);
  std::copy(v.tau.begin(), v.tau.end(), image.begin() + 3 * n);
  const std::vector<float>* tg[4] = {&v.mask, &v.weight, &v.angle, &v.confidence};
  for (int k = 0; k < 4; ++k) std::copy(tg[k]->begin(), tg[k]->end(), targets.begin() + 3 + k * n);
  gpu::Buffer<float> d_image(ctx, std::span<const float>(image), "image"), d_targets(ctx, std::span<const float>(targets), "targets");
  gpu::Buffer<float> d_grad(ctx, 5 * n, "grad image"), d_losses(ctx, 4, "losses");
  d_grad.fill_u32(0x7fc00000u);  // NaN: every written float must be overwritten
  gpu::Stream s(ctx);
  const ImageLossInputBuffers in{d_image.range(0, n), d_image.range(n, 2 * n), d_image.range(3 * n, n)};
  const ImageLossTargetBuffers t{d_targets.range(3, n), d_targets.range(3 + n, n), d_targets.range(3 + 2 * n, n),
                                 d_targets.range(3 + 3 * n, n)};
  image_losses_forward(s, v.size, {}, in, t, d_losses);
  image_losses_backward(s, v.size, {}, in, t, d_losses, 0.1f, 1000.f,
                        {d_grad.range(0, n), d_grad.range(n, 2 * n), d_grad.range(3 * n, n)});
  s.submit_and_wait();
  const auto expect = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 0.1f, 1000.f);
  const auto losses = d_losses.download();
  CHECK(losses[0] == expect.values.silhouette);
  CHECK(losses[1] == expect.values.orientation);
  const auto grad = d_grad.download();
  for (std::uint64_t i = 0; i < n; ++i) {
    CHECK(grad[i] == expect.grads.alpha[i]);
    CHECK(grad[n + i] == expect.grads.orientation[i]);
    CHECK(grad[2 * n + i] == expect.grads.orientation[n + i]);
    CHECK(grad[3 * n + i] == expect.grads.tau[i]);
    CHECK(std::isnan(grad[4 * n + i]));  // the depth plane is not touched
  }
}

TEST_CASE("1920x1080: GPU matches the double reference, finite; timing") {
  auto& ctx = test::context();
  View v(1920, 1080, 8);
  const std::uint64_t n = v.size.pixels();
  const auto r = image_losses_with_gradients(ctx, v.size, v.inputs(), v.targets(), 0.1f, 1000.f);
  const auto ref = reference(v, 0.1, 1000.0);
  REQUIRE(finite(r.grads.alpha));
  REQUIRE(finite(r.grads.orientation));
  REQUIRE(finite(r.grads.tau));
  CHECK(std::fabs(r.values.silhouette - ref.values.silhouette) <= 1e-4 * ref.values.silhouette);
  CHECK(std::fabs(r.values.orientation - ref.values.orientation) <= 1e-4 * ref.values.orientation);
  // Gradients per pixel, away from the kinks where float and double may take different sides.
  std::vector<bool> at_kink(n, false);
  std::size_t kinks = 0;
  for (std::uint64_t i = 0; i < n; ++i) {
    const double beta = 0.5 * std::atan2(double(v.orientation[n + i]), double(v.orientation[i]));
    const double d = beta - v.angle[i], rr = d - kPi * std::floor(d / kPi);
    const double far = std::min({rr, std::fabs(rr - kPi / 2), kPi - rr});
    at_kink[i] = far < 1e-4 || std::fabs(double(v.alpha[i]) - v.mask[i]) < 1e-6;
    kinks += at_kink[i];
  }
  CHECK(kinks < n / 1000);
  const auto away = [&](std::size_t i) { return !at_kink[i % n]; };
  const double ea = rel_error(r.grads.alpha, ref.grads.alpha, away);
  const double eo = rel_error(r.grads.orientation, ref.grads.orientation, away);
  const double et = rel_error(r.grads.tau, ref.grads.tau, away);
  MESSAGE("1920x1080 relative errors: alpha " << ea << ", orientation " << eo << ", tau " << et << " (" << kinks
                                              << " pixels at kinks)");
  CHECK(ea < 1e-4);
  CHECK(eo < 1e-4);
  CHECK(et < 1e-4);

  // Forward + backward on device-resident buffers, one submit each.
  gpu::Buffer<float> a(ctx, std::span<const float>(v.alpha), "alpha"), o(ctx, std::span<const float>(v.orientation), "o"),
      t(ctx, std::span<const float>(v.tau), "tau"), m(ctx, std::span<const float>(v.mask), "mask"),
      w(ctx, std::span<const float>(v.weight), "weight"), g(ctx, std::span<const float>(v.angle), "angle"),
      c(ctx, std::span<const float>(v.confidence), "confidence");
  gpu::Buffer<float> losses(ctx, 4, "losses"), ga(ctx, n, "ga"), go(ctx, 2 * n, "go"), gt(ctx, n, "gt");
  gpu::Stream s(ctx);
  double fwd_ms = 1e30, bwd_ms = 1e30;
  const auto run = [&] {
    s.begin_pass("image losses forward");
    image_losses_forward(s, v.size, {}, {a, o, t}, {m, w, g, c}, losses);
    s.end_pass();
    s.begin_pass("image losses backward");
    image_losses_backward(s, v.size, {}, {a, o, t}, {m, w, g, c}, losses, 0.1f, 1000.f, {ga, go, gt});
    s.end_pass();
    s.submit_and_wait();
    const auto& times = s.last_pass_times();
    REQUIRE(times.size() == 2);
    fwd_ms = std::min(fwd_ms, times[0].milliseconds);
    bwd_ms = std::min(bwd_ms, times[1].milliseconds);
  };
  run();  // warm-up: pipelines built
  const int reps = 5;
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < reps; ++k) run();
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / reps;
  MESSAGE("1920x1080: GPU forward " << fwd_ms << " ms, backward " << bwd_ms << " ms (best of " << reps
                                    << "); wall per forward + backward submit " << ms << " ms");
  CHECK(ga.download() == r.grads.alpha);
}

TEST_CASE("an empty image gives zero losses") {
  auto& ctx = test::context();
  const std::vector<float> none;
  const auto r = image_losses_with_gradients(ctx, {0, 5}, {none, none, none}, {none, none, none, none}, 1.f, 1.f);
  CHECK(r.values.silhouette == 0.f);
  CHECK(r.values.orientation == 0.f);
  CHECK(r.grads.alpha.empty());
}

TEST_CASE("bad input is rejected with an error naming it") {
  auto& ctx = test::context();
  const auto message = [&](View v) -> std::string {
    try {
      (void)image_losses(ctx, v.size, v.inputs(), v.targets());
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  View v(4, 3, 9);
  View nan_tau = v;
  nan_tau.tau[5] = NAN;
  CHECK(message(nan_tau).find("tau") != std::string::npos);
  View inf_o = v;
  inf_o.orientation[13] = INFINITY;
  CHECK(message(inf_o).find("orientation") != std::string::npos);
  View neg_w = v;
  neg_w.weight[2] = -0.5f;
  CHECK(message(neg_w).find("weight") != std::string::npos);
  View neg_c = v;
  neg_c.confidence[0] = -1.f;
  CHECK(message(neg_c).find("gabor_confidence") != std::string::npos);
  View short_o = v;
  short_o.orientation.resize(12);
  CHECK(message(short_o).find("orientation") != std::string::npos);
  ImageLossParams bad;
  bad.tau_floor = 0;
  CHECK_THROWS_AS((void)image_losses(ctx, v.size, v.inputs(), v.targets(), bad), InputError);
}
