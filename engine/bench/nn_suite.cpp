#include "engine/bench/nn_suite.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>

#include "engine/bench/core_suite.hpp"
#include "engine/bench/record.hpp"
#include "engine/core/log.hpp"
#include "engine/core/progress.hpp"
#include "engine/nn/adam.hpp"
#include "engine/nn/frequency_encoding.hpp"
#include "engine/nn/hash_grid.hpp"
#include "engine/nn/init.hpp"
#include "engine/nn/loss.hpp"
#include "engine/nn/mlp.hpp"

namespace nf::bench {
namespace {

constexpr const char* kSuite = "nn";

enum class Encoding { None, Frequency, HashGrid };

struct NetSpec {
  std::string name;
  Encoding encoding;
  nn::MlpConfig mlp;
  std::uint32_t batch, quick_batch;
};

std::vector<NetSpec> nets() {
  nn::MlpConfig fur;
  fur.input_dim = 63;
  fur.hidden = {64, 128, 256, 256};
  fur.output_dim = 129;
  nn::MlpConfig sdf;
  sdf.input_dim = 32;
  sdf.hidden = {64, 64};
  sdf.output_dim = 16;  // SDF + 15 geometry features
  sdf.hidden_activation = {nn::Activation::Softplus, 100.f, 30.f};
  nn::MlpConfig decoder;  // the shape first benchmarked (and on the H100)
  decoder.input_dim = 64;
  decoder.hidden = {256, 256};
  decoder.output_dim = 297;
  nn::MlpConfig shipped = decoder;  // the shipped strand prior's decoder (engine/fur/strand_prior.hpp)
  shipped.hidden = {128, 128};
  return {{"fur_field", Encoding::Frequency, fur, 15000, 2048},
          {"neus_sdf", Encoding::HashGrid, sdf, 32768, 4096},
          {"strand_decoder", Encoding::None, decoder, 15000, 2048},
          {"strand_decoder_128", Encoding::None, shipped, 15000, 2048}};
}

std::string shape_text(const nn::MlpConfig& c) {
  std::string s = std::to_string(c.input_dim);
  for (auto h : c.hidden) s += "-" + std::to_string(h);
  return s + "-" + std::to_string(c.output_dim);
}

// PyTorch's CPU training step for the same MLP, from tools/bench_torch_nn.py (Debian's python3-torch).
json torch_peer(const std::string& script, const NetSpec& net, std::uint32_t batch, bool quick) {
  if (script.empty()) return json{{"available", false}, {"why", "no --torch-peer script given"}};
  std::string hidden;
  for (auto h : net.mlp.hidden) hidden += (hidden.empty() ? "" : ",") + std::to_string(h);
  const std::string command = "/usr/bin/python3 '" + script + "' --inputs " + std::to_string(net.mlp.input_dim) +
                              " --hidden " + hidden + " --outputs " + std::to_string(net.mlp.output_dim) +
                              " --activation " + nn::to_string(net.mlp.hidden_activation.type) + " --batch " +
                              std::to_string(batch) + " --steps " + (quick ? "3" : "7") + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return json{{"available", false}, {"why", "cannot start /usr/bin/python3"}};
  std::string out;
  char buffer[4096];
  while (std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) out.append(buffer, n);
  const int status = pclose(pipe);
  try {
    if (status == 0) return json::parse(out.substr(out.find('{')));
  } catch (const std::exception&) {
  }
  return json{{"available", false}, {"why", out.substr(0, 300)}};
}

json bench_net(gpu::Context& ctx, const NetSpec& net, const Options& options, double fma_gflops) {
  const std::uint32_t batch = options.quick ? net.quick_batch : net.batch;
  const int repeats = options.quick ? 2 : 5;
  nn::Mlp mlp(ctx, net.mlp);
  mlp.parameters().upload(nn::initial_parameters(net.mlp, {nn::InitScheme::KaimingUniform, 1}));
  nn::Adam adam(ctx, net.mlp.parameter_count(), {}, {});
  nn::Mlp::Workspace ws(mlp, batch);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.f, 1.f);

  // Inputs as the pipeline has them: points for the encodings, latents for the decoder.
  const std::uint32_t raw_dims = net.encoding == Encoding::None ? mlp.input_stride() : 3;
  std::vector<float> raw(std::size_t(raw_dims) * batch);
  for (float& x : raw) x = u(rng);
  std::vector<float> target(std::size_t(net.mlp.output_dim) * batch);
  for (float& x : target) x = u(rng) - 0.5f;
  gpu::Buffer<float> d_raw(ctx, std::span<const float>(raw), "bench inputs");
  gpu::Buffer<float> d_target(ctx, std::span<const float>(target), "bench targets");
  gpu::Buffer<float> encoded(ctx, std::uint64_t(mlp.input_stride()) * batch, "bench encoded");
  gpu::Buffer<float> grad_out(ctx, std::uint64_t(mlp.output_stride()) * batch, "bench grad out");
  gpu::Buffer<float> grad_in(ctx, std::uint64_t(mlp.input_stride()) * batch, "bench grad in");
  gpu::Buffer<float> loss(ctx, 1, "bench loss");

  nn::FrequencyEncoding frequency({3, 10, true});
  nn::HashGridConfig gc;  // 16 levels x 2 features, 2^19 entries, 16..2048
  nn::HashGrid grid(gc);
  std::unique_ptr<gpu::Buffer<float>> table, table_grad;
  std::unique_ptr<nn::Adam> table_adam;
  if (net.encoding == Encoding::HashGrid) {
    table = std::make_unique<gpu::Buffer<float>>(ctx, std::span<const float>(grid.initial_table(2)), "bench table");
    table_grad = std::make_unique<gpu::Buffer<float>>(ctx, gc.parameter_count(), "bench table grad");
    nn::AdamConfig tc;
    tc.eps = 1e-15f;
    table_adam = std::make_unique<nn::Adam>(ctx, gc.parameter_count(), tc, std::vector<nn::ParamGroup>{});
  }
  const gpu::BufferRange input = net.encoding == Encoding::None ? d_raw.whole() : encoded.whole();

  gpu::Stream s(ctx);
  std::vector<float> losses;
  std::vector<double> step_seconds;
  const Timing train = time_repeats(repeats, nullptr, [&] {
    const auto start = std::chrono::steady_clock::now();
    if (losses.size() == 1) ctx.reset_pass_totals();  // the warm-up step's passes do not count
    if (net.encoding != Encoding::None) {
      gpu::ScopedPass pass(s, "encoding");
      if (net.encoding == Encoding::Frequency) frequency.forward(s, d_raw, encoded, batch);
      if (net.encoding == Encoding::HashGrid) {
        s.fill(table_grad->whole(), 0);
        grid.forward(s, d_raw, *table, encoded, batch);
      }
    }
    {
      gpu::ScopedPass pass(s, "mlp forward");
      mlp.forward(s, ws, input);
    }
    {
      gpu::ScopedPass pass(s, "loss");
      nn::mse_loss(s, ws.output(), d_target, grad_out, loss, batch, net.mlp.output_dim, mlp.output_stride());
    }
    {
      gpu::ScopedPass pass(s, "mlp backward");
      const bool need_input_grad = net.encoding == Encoding::HashGrid;
      mlp.backward(s, ws, input, grad_out, need_input_grad ? grad_in.whole() : gpu::BufferRange{}, false);
    }
    if (net.encoding == Encoding::HashGrid) {
      gpu::ScopedPass pass(s, "encoding backward");
      grid.backward(s, d_raw, *table, grad_in, *table_grad, {}, batch, false);
    }
    {
      gpu::ScopedPass pass(s, "adam");
      adam.step(s, mlp.parameters(), mlp.gradients(), 1e-3f);
      if (table_adam) table_adam->step(s, *table, *table_grad, 1e-2f);
    }
    s.submit_and_wait();
    losses.push_back(loss.download()[0]);
    step_seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    return -1.0;
  });
  const json step_device_ms = pass_ms_per_run(ctx, repeats);  // where a step goes on the device
  const double mlp_flops = double(batch) * (mlp.forward_flops_per_sample() + mlp.backward_flops_per_sample());
  const double train_gflops = mlp_flops / train.median() / 1e9;

  gpu::Buffer<float> out(ctx, std::uint64_t(mlp.output_stride()) * batch, "bench inference out");
  const Timing infer = time_repeats(repeats, nullptr, [&] {
    mlp.infer(s, input, out, batch);
    s.submit_and_wait();
    return -1.0;
  });
  const double infer_gflops = double(batch) * mlp.forward_flops_per_sample() / infer.median() / 1e9;

  json metrics{{"train_samples_per_s", batch / train.median()},
               {"train_mlp_GFLOPs", train_gflops},
               {"train_fraction_of_fma", train_gflops / fma_gflops},
               {"infer_samples_per_s", batch / infer.median()},
               {"infer_GFLOPs", infer_gflops},
               {"infer_fraction_of_fma", infer_gflops / fma_gflops},
               {"device_fma_GFLOPs", fma_gflops},
               {"train_device_ms", step_device_ms},
               {"loss_first", losses.front()},
               {"loss_last", losses.back()},
               {"loss_finite", std::isfinite(losses.back())}};
  const json peer = torch_peer(options.torch_peer, net, batch, options.quick);
  metrics["torch_peer"] = peer;
  if (peer.value("available", false)) {
    const double torch_step = peer["train_seconds_per_step"].get<double>();
    metrics["train_speedup_vs_torch_cpu"] = torch_step / train.median();
  }
  json params{{"mlp", shape_text(net.mlp)},
              {"encoding", net.encoding == Encoding::Frequency ? "frequency(10)"
                           : net.encoding == Encoding::HashGrid ? "hash_grid(16x2, 2^19)"
                                                                : "none"},
              {"batch", batch},
              {"step", "encoding + mlp forward, mse, mlp backward (+ encoding backward), AdamW"}};
  json record = make_record(ctx, kSuite, net.name + "_train", params, train, metrics);
  // Error against time: the training loss after each step (warm-up included), at cumulative seconds.
  json curve = json::array();
  double elapsed = 0;
  for (std::size_t i = 0; i < losses.size(); ++i) curve.push_back({elapsed += step_seconds[i], losses[i]});
  record["curve"] = {{"x", "seconds"}, {"y", "training loss (mse)"}, {"points", curve}};
  return record;
}

}  // namespace

json run_nn_suite(gpu::Context& context, const Options& options) {
  json records = json::array();
  const double fma = measure_fma_gflops(context, options.quick);
  const auto specs = nets();
  Progress progress("bench nn", specs.size());
  std::uint64_t done = 0;
  for (const NetSpec& net : specs) {
    records.push_back(bench_net(context, net, options, fma));
    progress.update(++done, net.name);
  }
  progress.finish("done");
  return records;
}

}  // namespace nf::bench
