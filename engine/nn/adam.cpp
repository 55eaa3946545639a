#include "engine/nn/adam.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "engine/core/error.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::nn {
namespace {

struct StatsPush {
  std::uint32_t count, per_group;
};
struct PreparePush {
  std::uint32_t groups;
  float max_norm, beta1, beta2;
};
struct StepPush {
  std::uint32_t offset, count;
  float lr, weight_decay, beta1, beta2, eps;
};
constexpr std::uint32_t kStatsGroups = 256;
constexpr std::uint32_t kStateWords = 7;  // taken, skipped, skip, clip, norm, beta1^t, beta2^t

}  // namespace

float LearningRateSchedule::at(std::uint64_t step) const {
  if (warmup > 0 && step < warmup) return base * float(step + 1) / float(warmup);
  if (total <= warmup) return base;
  const double progress = std::min(1.0, double(step - warmup) / double(total - warmup));
  return base * float(floor + (1.0 - floor) * 0.5 * (1.0 + std::cos(3.14159265358979323846 * progress)));
}

Adam::Adam(gpu::Context& context, std::uint64_t parameter_count, const AdamConfig& config,
           std::vector<ParamGroup> groups)
    : context_(context), count_(parameter_count), config_(config), groups_(std::move(groups)) {
  if (groups_.empty()) groups_.push_back({0, parameter_count, 1.f, 0.f});
  for (const ParamGroup& g : groups_)
    if (g.offset + g.count > parameter_count)
      throw InputError("optimiser parameter group [" + std::to_string(g.offset) + ", " +
                       std::to_string(g.offset + g.count) + ") lies outside the " + std::to_string(parameter_count) +
                       " parameters");
  if (!(config.beta1 >= 0 && config.beta1 < 1 && config.beta2 >= 0 && config.beta2 < 1 && config.eps > 0))
    throw InputError("optimiser: betas must lie in [0, 1) and eps be positive");
  m_ = std::make_unique<gpu::Buffer<float>>(context, parameter_count, "adam first moment");
  v_ = std::make_unique<gpu::Buffer<float>>(context, parameter_count, "adam second moment");
  state_ = std::make_unique<gpu::Buffer<std::uint32_t>>(context, kStateWords, "adam state");
  reset();
}

Adam::State Adam::save_state() const { return {m_->download(), v_->download(), state_->download()}; }

void Adam::load_state(const State& state) {
  if (state.m.size() != count_ || state.v.size() != count_ || state.words.size() != kStateWords)
    throw InputError("optimiser state holds " + std::to_string(state.m.size()) + " moments and " +
                     std::to_string(state.words.size()) + " counters; expected " + std::to_string(count_) + " and " +
                     std::to_string(kStateWords));
  m_->upload(state.m);
  v_->upload(state.v);
  state_->upload(state.words);
}

void Adam::reset() {
  m_->fill_u32(0);
  v_->fill_u32(0);
  const std::uint32_t one = 0x3f800000u;  // 1.0f: beta^0
  state_->upload(std::vector<std::uint32_t>{0, 0, 0, one, 0, one, one});
}

void Adam::step(gpu::Stream& stream, gpu::BufferRange parameters, gpu::BufferRange gradients, float lr) {
  if (parameters.size / 4 < count_ || gradients.size / 4 < count_)
    throw InternalError("adam step: parameter or gradient range smaller than the parameter count");
  const gpu::Kernel& stats = context_.kernel("nn/grad_stats", {{0, 256}});
  const gpu::Kernel& prepare = context_.kernel("nn/adam_prepare");
  const gpu::Kernel& update = context_.kernel("nn/adam_step", {{0, 256}});
  const std::uint32_t per_group = std::uint32_t(std::max<std::uint64_t>(1, (count_ + kStatsGroups - 1) / kStatsGroups));
  const std::uint32_t groups = std::uint32_t((count_ + per_group - 1) / per_group);
  const gpu::BufferRange partials = stream.scratch(std::max(1u, groups) * 8, "gradient statistics");
  stream.dispatch_groups(stats, {gradients, partials}, StatsPush{std::uint32_t(count_), per_group},
                         gpu::Elements(std::max(1u, groups)));
  stream.dispatch_groups(prepare, {partials, state_->whole()}, PreparePush{groups, config_.max_grad_norm, config_.beta1, config_.beta2},
                         gpu::Elements(1));
  for (const ParamGroup& g : groups_) {
    if (g.count == 0) continue;
    stream.dispatch(update, {parameters, gradients, m_->whole(), v_->whole(), state_->whole()},
                    StepPush{std::uint32_t(g.offset), std::uint32_t(g.count), lr * g.lr_scale, g.weight_decay,
                             config_.beta1, config_.beta2, config_.eps},
                    gpu::Elements(g.count));
  }
}

Adam::Counters Adam::counters() const {
  const auto s = state_->download();
  Counters c;
  c.taken = s[0];
  c.skipped = s[1];
  std::memcpy(&c.last_clip, &s[3], 4);
  std::memcpy(&c.last_norm, &s[4], 4);
  return c;
}

void add_state_tensors(const Adam::State& state, const std::string& prefix, WeightsFile& file) {
  std::vector<float> words(state.words.size());
  std::memcpy(words.data(), state.words.data(), words.size() * 4);
  file.tensors.push_back({prefix + ".m", {state.m.size()}, state.m});
  file.tensors.push_back({prefix + ".v", {state.v.size()}, state.v});
  file.tensors.push_back({prefix + ".state", {words.size()}, std::move(words)});
}

Adam::State state_from_tensors(const WeightsFile& file, const std::string& prefix, const std::filesystem::path& source) {
  Adam::State s{file.tensor(prefix + ".m", source).values, file.tensor(prefix + ".v", source).values, {}};
  const std::vector<float>& words = file.tensor(prefix + ".state", source).values;
  s.words.resize(words.size());
  std::memcpy(s.words.data(), words.data(), words.size() * 4);
  return s;
}

}  // namespace nf::nn
