#include "engine/fur/prior_training.hpp"

#include <chrono>
#include <cmath>
#include <random>

#include "engine/core/error.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/gpu/context.hpp"
#include "engine/nn/adam.hpp"
#include "engine/nn/adam_ref.hpp"
#include "engine/nn/init.hpp"

namespace nf::fur {
namespace {

// Standard normal numbers from 64-bit draws (Box-Muller): the same on every standard library.
struct Gaussian {
  std::mt19937_64 rng;
  double uniform() { return (double(rng() >> 11) + 0.5) * (1.0 / 9007199254740992.0); }
  float operator()() { return float(std::sqrt(-2.0 * std::log(uniform())) * std::cos(6.283185307179586 * uniform())); }
};

std::vector<float> rows_of(const gpu::BufferRange& range) {
  std::vector<float> out(range.size / sizeof(float));
  range.buffer->read_bytes(range.offset, out.data(), range.size);
  return out;
}

// Mean over points 1..99 of the squared distance, and its gradient with respect to the points
// (scaled by `scale`); the mean Euclidean distance per point goes to `mean_distance`.
double point_loss(const std::vector<float>& predicted, const std::vector<float>& truth, std::uint32_t count, float scale,
                  std::vector<float>& grad, double& mean_distance) {
  grad.assign(predicted.size(), 0.0f);
  double loss = 0, distance = 0;
  for (std::uint32_t k = 0; k < count; ++k)
    for (std::uint32_t i = 1; i < kStrandPoints; ++i) {
      const std::size_t at = (std::size_t(k) * kStrandPoints + i) * 3;
      double d2 = 0;
      for (int c = 0; c < 3; ++c) {
        const float d = predicted[at + c] - truth[at + c];
        d2 += double(d) * d;
        grad[at + c] = scale * 2.0f * d;
      }
      loss += d2, distance += std::sqrt(d2);
    }
  mean_distance = distance / (double(count) * kStrandPoints);
  return loss;
}

}  // namespace

PriorTraining train_strand_prior(gpu::Context& ctx, const PriorTrainingOptions& o,
                                 const std::function<void(std::uint32_t, double)>& progress) {
  PriorTraining out;
  out.prior = std::make_unique<StrandPrior>(ctx, o.shape);
  nn::Mlp& enc = out.prior->encoder();
  nn::Mlp& dec = out.prior->decoder();
  enc.parameters().upload(nn::initial_parameters(enc.config(), {nn::InitScheme::KaimingUniform, unsigned(o.seed)}));
  dec.parameters().upload(nn::initial_parameters(dec.config(), {nn::InitScheme::KaimingUniform, unsigned(o.seed + 1)}));
  nn::AdamConfig ac;
  ac.max_grad_norm = 1.0f;  // a rare batch of extreme curls must not throw the networks off
  nn::Adam adam_e(ctx, enc.config().parameter_count(), ac, {}), adam_d(ctx, dec.config().parameter_count(), ac, {});
  const nn::LearningRateSchedule schedule{o.lr, o.warmup, o.steps, o.lr_floor};

  const std::uint32_t B = o.batch, L = o.shape.latent;
  const std::uint32_t es = enc.input_stride(), lo = enc.output_stride(), di = dec.input_stride(), dout = dec.output_stride();
  gpu::Buffer<float> input(ctx, std::uint64_t(es) * B, "prior strands"), latents(ctx, std::uint64_t(di) * B, "prior latents");
  gpu::Buffer<float> grad_rows(ctx, std::uint64_t(dout) * B, "prior dL/dsegments"), grad_z(ctx, std::uint64_t(di) * B, "prior dL/dz");
  gpu::Buffer<float> grad_mu(ctx, std::uint64_t(lo) * B, "prior dL/dmu");
  nn::Mlp::Workspace ws_e(enc, B), ws_d(dec, B);
  gpu::Stream s(ctx);
  Gaussian noise{std::mt19937_64(o.seed * 0x2545F4914F6CDD1Dull + 7)};
  const float point_scale = 1.0f / float(B * kStrandSegments);
  const auto start = std::chrono::steady_clock::now();

  for (std::uint32_t step = 0; step < o.steps; ++step) {
    if (interrupted()) throw Interrupted("train-prior: stopped at step " + std::to_string(step));
    // Training strands never repeat and never meet the held-out sets (evaluate_prior's seeds).
    const std::vector<float> truth = generate_strands(B, o.seed * 1000003ull + step);
    input.upload(encoder_rows(truth, es));
    enc.forward(s, ws_e, input);
    s.submit_and_wait();
    const std::vector<float> mu = rows_of(ws_e.output());
    std::vector<float> z(std::size_t(di) * B, 0.0f);
    double l2 = 0;
    for (std::uint32_t k = 0; k < B; ++k)
      for (std::uint32_t j = 0; j < L; ++j) {
        const float m = mu[std::size_t(k) * lo + j];
        l2 += double(m) * m;
        z[std::size_t(k) * di + j] = m + o.latent_noise * noise();
      }
    latents.upload(z);
    dec.forward(s, ws_d, latents);
    s.submit_and_wait();
    const std::vector<float> rows = rows_of(ws_d.output());
    const std::vector<float> points = strands_from_rows(rows, dout, B);
    std::vector<float> grad_points;
    double mean_distance = 0;
    const double p_loss = point_loss(points, truth, B, point_scale, grad_points, mean_distance);
    std::vector<float> g = rows_gradient(grad_points, dout, B);
    double s_loss = 0;  // segments: 99 x (p_{i+1} - p_i) are unit vectors
    for (std::uint32_t k = 0; k < B; ++k)
      for (std::uint32_t i = 0; i < kStrandSegments; ++i)
        for (int c = 0; c < 3; ++c) {
          const std::size_t t = (std::size_t(k) * kStrandPoints + i) * 3 + std::size_t(c);
          const float target = float(kStrandSegments) * (truth[t + 3] - truth[t]);
          const float d = rows[std::size_t(k) * dout + 3 * i + std::size_t(c)] - target;
          s_loss += double(d) * d;
          g[std::size_t(k) * dout + 3 * i + std::size_t(c)] += o.segment_weight * point_scale * 2.0f * d;
        }
    grad_rows.upload(g);
    dec.backward(s, ws_d, latents, grad_rows, grad_z, false);
    s.submit_and_wait();
    const std::vector<float> gz = grad_z.download();
    std::vector<float> gm(std::size_t(lo) * B, 0.0f);
    for (std::uint32_t k = 0; k < B; ++k)
      for (std::uint32_t j = 0; j < L; ++j)
        gm[std::size_t(k) * lo + j] = gz[std::size_t(k) * di + j] + o.latent_l2 * 2.0f * mu[std::size_t(k) * lo + j] / float(B);
    grad_mu.upload(gm);
    enc.backward(s, ws_e, input, grad_mu, {}, false);
    const float lr = schedule.at(step);
    adam_e.step(s, enc.parameters(), enc.gradients(), lr);
    adam_d.step(s, dec.parameters(), dec.gradients(), lr);
    s.submit_and_wait();

    const double loss = (p_loss + o.segment_weight * s_loss) * point_scale + o.latent_l2 * l2 / B;
    if (step % o.curve_every == 0 || step + 1 == o.steps) {
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      out.curve.push_back({step + 1, seconds, loss, mean_distance});
      if (progress) progress(step + 1, loss);
    }
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.skipped_steps = adam_e.counters().skipped + adam_d.counters().skipped;
  return out;
}

PointError reconstruction_error(StrandPrior& prior, const std::vector<float>& strands) {
  return point_error(prior.decode(prior.encode(strands)), strands);
}

LatentFit fit_latents(StrandPrior& prior, const std::vector<float>& strands, std::uint32_t iterations, float lr,
                      bool from_encoder) {
  const std::uint32_t n = std::uint32_t(strands.size() / (3 * kStrandPoints)), L = prior.config().latent;
  nn::Mlp& dec = prior.decoder();
  gpu::Context& ctx = dec.parameters().context();
  const std::uint32_t di = dec.input_stride(), dout = dec.output_stride();
  LatentFit fit;
  fit.latents = from_encoder ? prior.encode(strands) : std::vector<float>(std::size_t(n) * L, 0.0f);
  nn::Mlp::Workspace ws(dec, n);
  gpu::Buffer<float> z(ctx, std::uint64_t(di) * n, "fit latents"), grad_rows(ctx, std::uint64_t(dout) * n, "fit dL/drows");
  gpu::Buffer<float> grad_z(ctx, std::uint64_t(di) * n, "fit dL/dz");
  gpu::Stream s(ctx);
  nn::AdamStateRef<float> state;
  const nn::AdamConfig ac;
  for (std::uint32_t it = 0; it < iterations; ++it) {
    std::vector<float> rows_in(std::size_t(di) * n, 0.0f);
    for (std::uint32_t k = 0; k < n; ++k) std::copy_n(&fit.latents[std::size_t(k) * L], L, &rows_in[std::size_t(k) * di]);
    z.upload(rows_in);
    dec.forward(s, ws, z);
    s.submit_and_wait();
    const std::vector<float> points = strands_from_rows(rows_of(ws.output()), dout, n);
    std::vector<float> grad_points;
    double mean_distance = 0;
    // Per strand the mean over its points: each strand's latent sees its own loss at full scale.
    point_loss(points, strands, n, 1.0f / float(kStrandSegments), grad_points, mean_distance);
    fit.curve.push_back(mean_distance);
    grad_rows.upload(rows_gradient(grad_points, dout, n));
    dec.backward(s, ws, z, grad_rows, grad_z, false);
    s.submit_and_wait();
    const std::vector<float> gz = grad_z.download();
    std::vector<float> g(std::size_t(n) * L);
    for (std::uint32_t k = 0; k < n; ++k) std::copy_n(&gz[std::size_t(k) * di], L, &g[std::size_t(k) * L]);
    nn::adam_step_ref(fit.latents, g, state, ac, {nn::ParamGroup{0, fit.latents.size(), 1.0f, 0.0f}}, lr);
  }
  fit.error = point_error(prior.decode(fit.latents), strands);
  return fit;
}

}  // namespace nf::fur
