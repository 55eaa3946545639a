// AdamW on the GPU against its CPU reference: groups, weight decay, clipping, bias correction, the
// non-finite skip, and the learning-rate schedule.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "engine/core/error.hpp"
#include "engine/nn/adam.hpp"
#include "engine/nn/adam_ref.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::nn;

TEST_CASE("AdamW steps match the reference, with groups, weight decay and clipping") {
  auto& ctx = test::context();
  const std::uint64_t n = 1003;
  AdamConfig config;
  config.max_grad_norm = 3.f;
  const std::vector<ParamGroup> groups = {{0, 500, 1.f, 0.01f}, {500, 503, 0.1f, 0.f}};
  Adam adam(ctx, n, config, groups);
  std::mt19937 rng(3);
  std::normal_distribution<float> normal(0.f, 1.f);
  std::vector<float> params(n);
  for (float& p : params) p = normal(rng);
  std::vector<double> params_ref(params.begin(), params.end());
  AdamStateRef<double> state;
  gpu::Buffer<float> d_params(ctx, std::span<const float>(params), "params");
  gpu::Buffer<float> d_grads(ctx, n, "grads");
  gpu::Stream s(ctx);
  for (int step = 0; step < 6; ++step) {
    std::vector<float> grads(n);
    const float scale = step % 2 ? 0.01f : 1.f;  // alternately under and over the clipping norm
    for (float& g : grads) g = scale * normal(rng);
    d_grads.upload(grads);
    adam.step(s, d_params, d_grads, 1e-2f);
    s.submit_and_wait();
    adam_step_ref<double>(params_ref, std::vector<double>(grads.begin(), grads.end()), state, config, groups, 1e-2);
  }
  const auto got = d_params.download();
  double worst = 0;
  for (std::uint64_t i = 0; i < n; ++i) worst = std::max(worst, std::fabs(got[i] - params_ref[i]));
  CHECK(worst < 2e-5);
  const auto c = adam.counters();
  CHECK(c.taken == 6);
  CHECK(c.skipped == 0);
}

TEST_CASE("a step with a NaN or Inf gradient is skipped on the GPU and counted") {
  auto& ctx = test::context();
  const std::uint64_t n = 300;
  Adam adam(ctx, n, {}, {});
  std::vector<float> params(n, 1.f), grads(n, 0.5f);
  gpu::Buffer<float> d_params(ctx, std::span<const float>(params), "params");
  gpu::Buffer<float> d_grads(ctx, std::span<const float>(grads), "grads");
  gpu::Stream s(ctx);
  adam.step(s, d_params, d_grads, 0.1f);
  s.submit_and_wait();
  const auto after_one = d_params.download();
  CHECK(after_one[0] == doctest::Approx(0.9f));  // first Adam step moves by lr
  for (float bad : {NAN, INFINITY}) {
    grads[123] = bad;
    d_grads.upload(grads);
    adam.step(s, d_params, d_grads, 0.1f);
    s.submit_and_wait();
    CHECK(d_params.download() == after_one);
  }
  auto c = adam.counters();
  CHECK(c.taken == 1);
  CHECK(c.skipped == 2);
  grads[123] = 0.5f;
  d_grads.upload(grads);
  adam.step(s, d_params, d_grads, 0.1f);
  s.submit_and_wait();
  c = adam.counters();
  CHECK(c.taken == 2);
  CHECK(d_params.download()[0] == doctest::Approx(0.8f));
}

TEST_CASE("warm-up then cosine learning-rate schedule") {
  LearningRateSchedule sched{1e-3f, 10, 110, 0.1f};
  CHECK(sched.at(0) == doctest::Approx(1e-4));
  CHECK(sched.at(9) == doctest::Approx(1e-3));
  CHECK(sched.at(10) == doctest::Approx(1e-3));
  CHECK(sched.at(60) == doctest::Approx(0.55e-3));
  CHECK(sched.at(110) == doctest::Approx(1e-4));
  CHECK(sched.at(1000) == doctest::Approx(1e-4));
  LearningRateSchedule constant{2e-3f, 0, 0, 0.1f};
  CHECK(constant.at(12345) == doctest::Approx(2e-3));
}

TEST_CASE("parameter groups outside the parameters are rejected") {
  auto& ctx = test::context();
  CHECK_THROWS_WITH_AS(Adam(ctx, 10, {}, {{5, 6, 1.f, 0.f}}), doctest::Contains("outside the 10 parameters"),
                       InputError);
}

TEST_CASE("optimiser state saved and loaded continues bit for bit; a wrong size is refused") {
  auto& ctx = test::context();
  const std::uint64_t n = 257;
  const auto grads = test::random_f32(n, 9);
  const auto start = test::random_f32(n, 10);
  gpu::Buffer<float> g(ctx, std::span<const float>(grads), "grads");
  gpu::Buffer<float> a(ctx, std::span<const float>(start), "a"), b(ctx, n, "b");
  gpu::Stream s(ctx);
  Adam first(ctx, n, {}, {});
  for (int i = 0; i < 3; ++i) first.step(s, a, g, 1e-2f);
  s.submit_and_wait();
  Adam second(ctx, n, {}, {});
  second.load_state(first.save_state());
  b.upload(a.download());
  first.step(s, a, g, 1e-2f);
  second.step(s, b, g, 1e-2f);
  s.submit_and_wait();
  CHECK(a.download() == b.download());
  CHECK(second.counters().taken == 4);
  Adam::State wrong = first.save_state();
  wrong.m.pop_back();
  CHECK_THROWS_AS(second.load_state(wrong), InputError);
}
