#pragma once
// AdamW on the GPU: bias correction, parameter groups (own lr scale and weight decay), global-norm
// gradient clipping, and steps skipped (and counted) when any gradient is NaN or Inf — decided on
// the GPU, so a training loop never waits for the host. Learning-rate schedules: warm-up then cosine.
// Shaders: shaders/nn/{grad_stats,adam_prepare,adam_step}.comp. CPU twin: adam_ref.hpp.
#include <cstdint>
#include <memory>
#include <vector>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/nn/weights_io.hpp"

namespace nf::nn {

struct AdamConfig {
  float beta1 = 0.9f;
  float beta2 = 0.999f;
  float eps = 1e-8f;
  float max_grad_norm = 0.f;  // 0: no clipping
};

struct ParamGroup {
  std::uint64_t offset = 0, count = 0;  // floats in the parameter array
  float lr_scale = 1.f;                 // multiplies the step's learning rate
  float weight_decay = 0.f;
};

// Linear warm-up to the base rate, then cosine decay to `floor` times it at `total` steps.
struct LearningRateSchedule {
  float base = 1e-3f;
  std::uint64_t warmup = 0;
  std::uint64_t total = 0;  // 0: constant after warm-up
  float floor = 0.1f;
  float at(std::uint64_t step) const;
};

class Adam {
 public:
  Adam(gpu::Context& context, std::uint64_t parameter_count, const AdamConfig& config, std::vector<ParamGroup> groups);

  // Records one step on `parameters` from `gradients` (both parameter_count floats) at rate `lr`.
  void step(gpu::Stream& stream, gpu::BufferRange parameters, gpu::BufferRange gradients, float lr);

  struct Counters {
    std::uint32_t taken = 0, skipped = 0;
    float last_norm = 0, last_clip = 1;
  };
  // Reads the GPU-side counters (the stream must have been submitted).
  Counters counters() const;
  void reset();

  // Moments and counters, for checkpoints: a resumed run continues exactly where it stopped.
  struct State {
    std::vector<float> m, v;
    std::vector<std::uint32_t> words;
  };
  State save_state() const;
  void load_state(const State& state);  // throws InputError when the sizes do not match

 private:
  gpu::Context& context_;
  std::uint64_t count_;
  AdamConfig config_;
  std::vector<ParamGroup> groups_;
  std::unique_ptr<gpu::Buffer<float>> m_, v_;
  std::unique_ptr<gpu::Buffer<std::uint32_t>> state_;
};

// Checkpoints: an optimiser's state as tensors PREFIX.m, PREFIX.v, PREFIX.state of a weights file
// (the counters' words stored bit for bit as floats), and back; InputError naming the file and
// tensor when one is missing.
void add_state_tensors(const Adam::State& state, const std::string& prefix, WeightsFile& file);
Adam::State state_from_tensors(const WeightsFile& file, const std::string& prefix, const std::filesystem::path& source);

}  // namespace nf::nn
