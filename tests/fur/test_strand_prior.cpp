// The strand prior: procedural strands (unit length, root at the origin, every style), the frame
// transform and resampling, the running sum and its adjoint, a tiny prior that learns, training
// that repeats exactly, the weights file, and the shipped prior's accuracy and smoothness.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <filesystem>
#include <random>

#include "engine/core/error.hpp"
#include "engine/fur/prior_evaluation.hpp"
#include "engine/fur/prior_training.hpp"
#include "engine/fur/strand_prior.hpp"
#include "engine/fur/strand_shapes.hpp"
#include "engine/nn/weights_io.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::fur;
namespace fs = std::filesystem;

namespace {

glm::vec3 point(const std::vector<float>& s, std::size_t strand, std::uint32_t k) {
  const std::size_t i = (strand * kStrandPoints + k) * 3;
  return {s[i], s[i + 1], s[i + 2]};
}

// Sum of the turning angles between consecutive segments (radians).
double turning(const std::vector<float>& s, std::size_t strand) {
  double sum = 0;
  for (std::uint32_t k = 1; k + 1 < kStrandPoints; ++k) {
    const glm::vec3 a = glm::normalize(point(s, strand, k) - point(s, strand, k - 1));
    const glm::vec3 b = glm::normalize(point(s, strand, k + 1) - point(s, strand, k));
    sum += std::acos(std::clamp(double(glm::dot(a, b)), -1.0, 1.0));
  }
  return sum;
}

PriorTrainingOptions tiny_options(std::uint32_t steps) {
  PriorTrainingOptions o;
  o.shape.encoder_hidden = o.shape.decoder_hidden = {64, 64};
  o.steps = steps, o.batch = 256, o.warmup = 20, o.curve_every = 10, o.lr = 3e-3f;
  return o;
}

}  // namespace

TEST_CASE("procedural strands: 100 points, root at the origin, unit length, every style its own shape") {
  const std::uint32_t n = 300;
  std::map<std::string, double> mean_turning, mean_tip_height;
  for (const StrandStyle style : strand_styles()) {
    CAPTURE(style_name(style));
    const std::vector<float> s = generate_strands(n, 3, style);
    REQUIRE(s.size() == std::size_t(n) * kStrandPoints * 3);
    for (std::size_t k = 0; k < n; ++k) {
      CHECK(glm::length(point(s, k, 0)) == 0.0f);
      double length = 0;
      for (std::uint32_t i = 1; i < kStrandPoints; ++i) length += glm::distance(point(s, k, i), point(s, k, i - 1));
      CHECK(length == doctest::Approx(1.0).epsilon(1e-4));
      mean_turning[style_name(style)] += turning(s, k) / n;
      mean_tip_height[style_name(style)] += point(s, k, kStrandPoints - 1).z / n;
    }
  }
  CHECK(mean_turning["straight"] < mean_turning["wavy"]);
  CHECK(mean_turning["wavy"] < mean_turning["curly"]);
  CHECK(mean_tip_height["lying_down"] < mean_tip_height["straight"]);
  // Headings cover the whole skin: the tips' directions on the tangent plane fill every quadrant.
  const std::vector<float> any = generate_strands(2000, 4);
  int quadrants[4] = {};
  for (std::size_t k = 0; k < 2000; ++k) {
    const glm::vec3 tip = point(any, k, kStrandPoints - 1);
    ++quadrants[(tip.x >= 0 ? 0 : 1) + (tip.y >= 0 ? 0 : 2)];
  }
  for (int q : quadrants) CHECK(q > 350);
  CHECK(generate_strands(5, 9) == generate_strands(5, 9));
  CHECK(generate_strands(5, 9) != generate_strands(5, 10));
}

TEST_CASE("a strand moved into its root's frame, resampled and made unit length") {
  // Five points along the world's x axis from (1, 2, 3), unevenly spaced, 2 units long; frame: N = x.
  const float line[] = {1, 2, 3, 1.1f, 2, 3, 1.5f, 2, 3, 2.9f, 2, 3, 3, 2, 3};
  std::vector<float> out(kStrandPoints * 3);
  REQUIRE(strand_in_frame(line, 5, {1, 2, 3}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}, out.data()));
  for (std::uint32_t k = 0; k < kStrandPoints; ++k) {
    CHECK(out[3 * k] == doctest::Approx(0.0).epsilon(1e-6));
    CHECK(out[3 * k + 1] == doctest::Approx(0.0).epsilon(1e-6));
    CHECK(out[3 * k + 2] == doctest::Approx(double(k) / 99).epsilon(1e-5));
  }
  const float dot[] = {1, 1, 1, 1, 1, 1};
  CHECK_FALSE(strand_in_frame(dot, 2, {1, 1, 1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, out.data()));
}

TEST_CASE("the running sum of decoded segments and its adjoint") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1, 1);
  const std::uint32_t n = 3, stride = 300;
  std::vector<float> rows(std::size_t(n) * stride), grad_points(std::size_t(n) * kStrandPoints * 3);
  for (float& v : rows) v = u(rng);
  for (float& v : grad_points) v = u(rng);
  // <g, J r> = <J^T g, r> for the linear map rows -> points (the root's gradient is ignored: it is fixed).
  const std::vector<float> points = strands_from_rows(rows, stride, n);
  const std::vector<float> back = rows_gradient(grad_points, stride, n);
  double lhs = 0, rhs = 0;
  for (std::uint32_t k = 0; k < n; ++k) {
    for (std::uint32_t i = 1; i < kStrandPoints; ++i)
      for (int c = 0; c < 3; ++c) lhs += double(grad_points[(k * kStrandPoints + i) * 3 + c]) * points[(k * kStrandPoints + i) * 3 + c];
    for (std::uint32_t j = 0; j < kStrandValues; ++j) rhs += double(back[k * stride + j]) * rows[k * stride + j];
  }
  CHECK(lhs == doctest::Approx(rhs).epsilon(1e-5));
  CHECK(point(points, 1, 1).x == doctest::Approx(rows[stride] / 99.0));
  for (std::uint32_t j = kStrandValues; j < stride; ++j) CHECK(back[j] == 0.0f);  // padding untouched
}

TEST_CASE("point error: the mean distance of corresponding points, per strand, then mean and p95") {
  std::vector<float> a = generate_strands(20, 1), b = a;
  for (std::size_t k = 0; k < 20; ++k)
    for (std::uint32_t i = 0; i < kStrandPoints; ++i) b[(k * kStrandPoints + i) * 3 + 2] += k == 19 ? 0.5f : 0.01f;
  const PointError e = point_error(b, a);
  CHECK(e.mean == doctest::Approx((19 * 0.01 + 0.5) / 20).epsilon(1e-4));
  CHECK(e.p95 == doctest::Approx(0.5).epsilon(1e-4));
}

TEST_CASE("a tiny prior learns, and training repeats exactly") {
  gpu::Context& ctx = test::context();
  PriorTraining t = train_strand_prior(ctx, tiny_options(300));
  const double first = t.curve.front()[2].get<double>(), last = t.curve.back()[2].get<double>();
  CHECK(last < 0.15 * first);
  CHECK(t.skipped_steps == 0);
  const PointError held_out = reconstruction_error(*t.prior, generate_strands(500, 777));
  MESSAGE("tiny prior after 300 steps: ", 100 * held_out.mean, " % mean, ", 100 * held_out.p95, " % p95 of the length");
  CHECK(held_out.mean < 0.06);
  // Fitting the latent through the decoder alone does better than the encoder's guess.
  const std::vector<float> synth = synth_strands_in_frames("dog", 200, 3);
  REQUIRE(synth.size() > 100 * kStrandPoints * 3);
  const LatentFit fit = fit_latents(*t.prior, synth, 60, 0.01f, true);
  CHECK(fit.curve.back() < fit.curve.front());
  CHECK(fit.error.mean < reconstruction_error(*t.prior, synth).mean);

  // The same seed: the same weights, bit for bit (no float atomics in the MLP kernels).
  const PriorTraining a = train_strand_prior(ctx, tiny_options(15)), b = train_strand_prior(ctx, tiny_options(15));
  CHECK(a.prior->decoder().parameters().download() == b.prior->decoder().parameters().download());
  CHECK(a.prior->encoder().parameters().download() == b.prior->encoder().parameters().download());

  // The weights file round-trips with its record, and refuses what is not a strand prior.
  const fs::path path = fs::temp_directory_path() / "nf_test_prior.nfwt";
  a.prior->record = {{"seed", 1}};
  a.prior->save(path);
  const auto loaded = StrandPrior::load(ctx, path);
  CHECK(loaded->decoder().parameters().download() == a.prior->decoder().parameters().download());
  CHECK(loaded->record["seed"] == 1);
  nn::save_weights(path, nn::mlp_weights(a.prior->config().decoder(), a.prior->decoder().parameters().download()));
  CHECK_THROWS_WITH_AS(StrandPrior::load(ctx, path), doctest::Contains("not a strand prior"), InputError);
  fs::remove(path);
}

TEST_CASE("the shipped prior: loaded from the binary, accurate on held-out and synthetic fur, smooth") {
  gpu::Context& ctx = test::context();
  const auto prior = shipped_strand_prior(ctx);
  CHECK(prior->config().latent == 64);
  CHECK(prior->record.contains("command"));
  CHECK(prior->record.contains("evaluation"));
  const PointError held_out = reconstruction_error(*prior, generate_strands(1000, 4242));
  MESSAGE("shipped prior, held-out strands: ", 100 * held_out.mean, " % mean, ", 100 * held_out.p95, " % p95");
  CHECK(held_out.mean < 0.03);
  // The target: at most 2 % of the length after fitting the latent, on synth fur.
  for (const char* animal : {"cat", "lion"}) {
    CAPTURE(animal);
    const LatentFit fit = fit_latents(*prior, synth_strands_in_frames(animal, 300, 8), 100, 0.01f, true);
    MESSAGE(std::string(animal), " fitted: ", 100 * fit.error.mean, " % mean, ", 100 * fit.error.p95, " % p95");
    CHECK(fit.error.mean < 0.02);
  }
  // Nearby latents, similar strands: a step of 0.1 in the latent moves points by a few % at most.
  const std::vector<float> z = prior->encode(generate_strands(200, 99));
  std::vector<float> moved = z;
  std::mt19937 rng(3);
  std::normal_distribution<float> g(0.0f, 1.0f);
  for (std::size_t k = 0; k < 200; ++k) {
    std::vector<float> d(64);
    float norm = 0;
    for (float& v : d) v = g(rng), norm += v * v;
    for (int j = 0; j < 64; ++j) moved[k * 64 + j] += 0.1f * d[j] / std::sqrt(norm);
  }
  const PointError shift = point_error(prior->decode(moved), prior->decode(z));
  MESSAGE("latent step of 0.1: points move by ", 100 * shift.mean, " % mean, ", 100 * shift.p95, " % p95");
  CHECK(shift.mean < 0.05);
  CHECK(shift.mean > 0.0);
}
