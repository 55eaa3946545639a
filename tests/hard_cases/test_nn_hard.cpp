// Hard cases of the nn kernels: precision of the frequency encoding far from the origin, zero-size
// batches, batches that are not a multiple of the workgroup, parameter gradients summed over
// several slabs with odd widths, Softplus at huge beta*x.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "engine/nn/frequency_encoding.hpp"
#include "engine/nn/mlp.hpp"
#include "engine/nn/mlp_ref.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::nn;

namespace {

// One forward and backward of `mlp` over `batch` samples, waited for; the workspace holds the output.
Mlp::Workspace training_pass(Mlp& mlp, std::uint32_t batch, const gpu::Buffer<float>& input,
                             const gpu::Buffer<float>& grad_output, const gpu::Buffer<float>& grad_input) {
  Mlp::Workspace ws(mlp, batch);
  gpu::Stream s(test::context());
  mlp.forward(s, ws, input);
  mlp.backward(s, ws, input, grad_output, grad_input, false);
  s.submit_and_wait();
  return ws;
}

}  // namespace

TEST_CASE("frequency encoding keeps float accuracy for |x| up to 1e3 at 2^9") {
  auto& ctx = test::context();
  const FrequencyEncodingConfig c{3, 10, false};
  const std::uint32_t batch = 1000;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1000.f, 1000.f);
  std::vector<float> pts(batch * 3);
  for (float& x : pts) x = u(rng);
  gpu::Buffer<float> points(ctx, std::span<const float>(pts), "points");
  gpu::Buffer<float> encoded(ctx, std::uint64_t(c.output_stride()) * batch, "encoded");
  gpu::Stream s(ctx);
  FrequencyEncoding(c).forward(s, points, encoded, batch);
  s.submit_and_wait();
  const auto got = encoded.download();
  const std::vector<double> pts_d(pts.begin(), pts.end());
  const auto truth = frequency_encoding_forward_ref<double>(c, pts_d, batch);
  double worst = 0;
  for (std::size_t i = 0; i < got.size(); ++i) {
    REQUIRE(std::isfinite(got[i]));
    worst = std::max(worst, std::fabs(double(got[i]) - truth[i]));
  }
  CHECK(worst < 2e-6);  // against the exact sin/cos of the float input, in double
}

TEST_CASE("an MLP handles empty batches and batches of any size") {
  auto& ctx = test::context();
  MlpConfig c;
  c.input_dim = 3;
  c.hidden = {16};
  c.output_dim = 2;
  Mlp mlp(ctx, c);
  std::vector<float> params(c.parameter_count(), 0.f);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  for (const LayerShape& l : c.layers())
    for (std::uint32_t o = 0; o < l.out; ++o) {
      for (std::uint32_t k = 0; k < l.in; ++k) params[l.weight_offset + o * l.in_stride + k] = u(rng);
      params[l.bias_offset + o] = u(rng);
    }
  mlp.parameters().upload(params);
  for (std::uint32_t batch : {0u, 1u, 63u, 65u, 1000u}) {
    CAPTURE(batch);
    std::vector<float> in(std::size_t(mlp.input_stride()) * batch, 0.f);
    for (std::uint32_t s = 0; s < batch; ++s)
      for (std::uint32_t k = 0; k < 3; ++k) in[s * mlp.input_stride() + k] = u(rng);
    gpu::Buffer<float> input(ctx, std::span<const float>(in), "input");
    gpu::Buffer<float> output(ctx, std::uint64_t(mlp.output_stride()) * batch, "output");
    gpu::Stream s(ctx);
    mlp.infer(s, input, output, batch);
    s.submit_and_wait();
    const auto got = output.download();
    const auto ref = mlp_forward_ref<float>(c, params, in, batch).y.back();
    REQUIRE(got.size() == ref.size());
    for (std::size_t i = 0; i < got.size(); ++i) CHECK(got[i] == doctest::Approx(ref[i]).epsilon(1e-5));
  }
}

// The layer kernel works in blocks of 32 output rows and at most 64 input vec4 per dispatch; the
// weight gradient in workgroups of at most 256 outputs x 32 inputs x one slab of 256 samples, then
// sums the slabs (with 32 KiB of shared memory; the _small_shared entry runs 16 KiB: 32 input vec4
// and 128 samples, so three chunks and 71 slabs below). Widths that are not multiples of a block,
// a layer wider than one chunk and than one workgroup of outputs, and an odd batch with a short
// last slab check every edge against the double-precision reference.
TEST_CASE("MLP gradients over several slabs and odd widths match the reference") {
  auto& ctx = test::context();
  MlpConfig c;
  c.input_dim = 300;     // 75 input vec4: two chunks of mlp_fwd; 10 input blocks, the last short
  c.hidden = {270, 36};  // 270 outputs: two weight-gradient workgroups; its input adjoint: 9 row blocks
  c.output_dim = 5;
  c.hidden_activation = {Activation::Softplus, 2.f, 30.f};
  Mlp mlp(ctx, c);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<double> params(c.parameter_count(), 0.0);
  for (const LayerShape& l : c.layers())
    for (std::uint32_t o = 0; o < l.out; ++o) {
      for (std::uint32_t k = 0; k < l.in; ++k) params[l.weight_offset + o * l.in_stride + k] = u(rng);
      params[l.bias_offset + o] = u(rng);
    }
  const std::uint32_t batch = 9001;  // 36 slabs, the last short; odd: a lone sample in its group of 8
  std::vector<double> in(std::size_t(mlp.input_stride()) * batch, 0.0);
  std::vector<double> grad_out(std::size_t(mlp.output_stride()) * batch, 0.0);
  for (std::uint32_t s = 0; s < batch; ++s) {
    for (std::uint32_t k = 0; k < c.input_dim; ++k) in[s * mlp.input_stride() + k] = u(rng);
    for (std::uint32_t o = 0; o < c.output_dim; ++o) grad_out[s * mlp.output_stride() + o] = u(rng);
  }
  const auto to_float = [](const std::vector<double>& v) { return std::vector<float>(v.begin(), v.end()); };
  mlp.parameters().upload(to_float(params));
  gpu::Buffer<float> input(ctx, std::span<const float>(to_float(in)), "input");
  gpu::Buffer<float> grad_output(ctx, std::span<const float>(to_float(grad_out)), "grad out");
  gpu::Buffer<float> grad_input(ctx, std::uint64_t(mlp.input_stride()) * batch, "grad in");
  training_pass(mlp, batch, input, grad_output, grad_input);

  const auto trace = mlp_forward_ref<double>(c, params, in, batch);
  std::vector<double> want_params(params.size(), 0.0);
  const auto want_input = mlp_backward_ref<double>(c, params, in, batch, trace, grad_out, want_params);
  const auto check = [](const std::vector<float>& got, const std::vector<double>& want, const char* what) {
    REQUIRE(got.size() == want.size());
    double scale = 0.0;
    for (double w : want) scale = std::max(scale, std::abs(w));
    std::size_t bad = 0;
    for (std::size_t i = 0; i < got.size(); ++i)
      if (std::abs(got[i] - want[i]) > 1e-4 * scale + 1e-5 * std::abs(want[i])) ++bad;
    INFO(what << ": largest |value| " << scale);
    CHECK(bad == 0);
  };
  check(mlp.gradients().download(), want_params, "parameter gradients");
  check(grad_input.download(), want_input, "input gradients");
}

TEST_CASE("Softplus at huge beta*x stays finite, forward and backward") {
  auto& ctx = test::context();
  MlpConfig c;
  c.input_dim = 1;
  c.hidden = {4};
  c.output_dim = 1;
  c.hidden_activation = {Activation::Softplus, 100.f, 30.f};
  Mlp mlp(ctx, c);
  std::vector<float> params(c.parameter_count(), 0.f);
  const LayerShape l0 = c.layers()[0], l1 = c.layers()[1];
  for (std::uint32_t o = 0; o < 4; ++o) params[l0.weight_offset + o * l0.in_stride] = o % 2 ? 1e3f : -1e3f;
  for (std::uint32_t k = 0; k < 4; ++k) params[l1.weight_offset + k] = 1.f;
  mlp.parameters().upload(params);
  const std::uint32_t batch = 3;
  std::vector<float> in = {1e3f, 0, 0, 0, -1e3f, 0, 0, 0, 0.f, 0, 0, 0};
  gpu::Buffer<float> input(ctx, std::span<const float>(in), "input");
  std::vector<float> ones(std::size_t(mlp.output_stride()) * batch, 0.f);
  for (std::uint32_t s = 0; s < batch; ++s) ones[s * mlp.output_stride()] = 1.f;
  gpu::Buffer<float> grad_out(ctx, std::span<const float>(ones), "grad out");
  gpu::Buffer<float> grad_in(ctx, std::uint64_t(mlp.input_stride()) * batch, "grad in");
  const Mlp::Workspace ws = training_pass(mlp, batch, input, grad_out, grad_in);
  std::vector<float> out(ws.output().size / 4);
  ws.output().buffer->read_bytes(0, out.data(), ws.output().size);
  for (float v : out) CHECK(std::isfinite(v));
  for (float v : grad_in.download()) CHECK(std::isfinite(v));
  for (float v : mlp.gradients().download()) CHECK(std::isfinite(v));
  CHECK(out[0] == doctest::Approx(2e6).epsilon(1e-4));  // two units pass 1e6 each, two are ~0
  // Hidden pre-activations are z = w x = +-1e6 (x = +-1e3) or 0 (x = 0). Softplus passes 1e6 (beta z
  // > 20: identity, slope 1) and gives 0 for -1e6 (exp(-1e8) = 0, slope 0); at 0 it is log(2) / beta
  // with slope 1/2. So sample 1 mirrors sample 0, and sample 2 outputs 4 log(2) / 100.
  const std::uint32_t out_row = mlp.output_stride(), in_row = mlp.input_stride();
  CHECK(out[out_row] == doctest::Approx(2e6).epsilon(1e-4));
  CHECK(out[2 * out_row] * 25 == doctest::Approx(std::log(2.0)).epsilon(1e-5));
  // dL/dout = 1 per sample and output weights 1, so dL/dz = the slopes: (0, 1, 0, 1) for x = 1e3,
  // (1, 0, 1, 0) for x = -1e3, 1/2 each for x = 0. dL/dx = sum_k slope_k w_k: 2e3, -2e3 and
  // (-1e3 + 1e3 - 1e3 + 1e3) / 2 = 0.
  const std::vector<float> gin = grad_in.download();
  CHECK(gin[0] == doctest::Approx(2e3).epsilon(1e-6));
  CHECK(gin[in_row] == doctest::Approx(-2e3).epsilon(1e-6));
  CHECK(gin[2 * in_row] == doctest::Approx(0.0).epsilon(1e-3));  // 0 +- the rounding of 4 terms of 500
  // Parameter gradients summed over the 3 samples: input weight k: sum slope x = w_k (each unit is
  // on for the one sample of its sign, and x = 0 adds nothing); its bias: 1 + 1/2; output weight k:
  // sum y = 1e6 + log(2) / 100; output bias: 3.
  const std::vector<float> grads = mlp.gradients().download();
  for (std::uint32_t k = 0; k < 4; ++k) {
    CAPTURE(k);
    const std::uint64_t w = l0.weight_offset + k * l0.in_stride;
    CHECK(grads[w] == doctest::Approx(params[w]).epsilon(1e-6));
    CHECK(grads[l0.bias_offset + k] == doctest::Approx(1.5).epsilon(1e-5));
    CHECK(grads[l1.weight_offset + k] == doctest::Approx(1e6 + std::log(2.0) / 100).epsilon(1e-6));
  }
  CHECK(grads[l1.bias_offset] == doctest::Approx(3.0).epsilon(1e-6));
}
