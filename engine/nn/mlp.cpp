#include "engine/nn/mlp.hpp"

#include <algorithm>

#include "engine/core/error.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::nn {
namespace {

// Register blocking of mlp_forward / mlp_backward_data (a shader variant) and its workgroup.
constexpr const char* kBlocking = "r1c8";
constexpr std::uint32_t kRows = 1;
constexpr std::uint32_t kWorkgroup = 64;
constexpr std::uint32_t kSlabItems = 32;  // samples per invocation in mlp_backward_weights
constexpr std::uint32_t kSlab = kWorkgroup * kSlabItems;
constexpr std::uint32_t kMaxInferenceChunk = 1u << 16;

struct ForwardPush {
  std::uint32_t batch, in_dim, out_dim, weight_offset, bias_offset, activation;
  float beta, omega;
  std::uint32_t store_z, input_sample_major, output_sample_major;
};
struct ActivationBackwardPush {
  std::uint32_t count, activation;
  float beta, omega;
};
struct BackwardDataPush {
  std::uint32_t batch, in_dim, out_dim, weight_offset, output_sample_major, accumulate;
};
struct BackwardWeightsPush {
  std::uint32_t batch, in_dim, out_dim, blocks_per_group;
};
struct ReducePartialsPush {
  std::uint32_t weights, biases, slabs, offset, accumulate;
};

gpu::Elements sample_groups(std::uint32_t batch) {
  const std::uint64_t per_group = std::uint64_t(kWorkgroup) * kRows;
  return gpu::Elements((batch + per_group - 1) / per_group * kWorkgroup);
}

std::uint64_t layer_parameters(const LayerShape& l) { return std::uint64_t(l.out) * l.in + l.out; }

}  // namespace

Mlp::Mlp(gpu::Context& context, const MlpConfig& config, const std::string& name)
    : context_(context), config_(config) {
  config_.validate();
  layers_ = config_.layers();
  parameters_ = std::make_unique<gpu::Buffer<float>>(context, config_.parameter_count(), name + " parameters");
  gradients_ = std::make_unique<gpu::Buffer<float>>(context, config_.parameter_count(), name + " gradients");
  parameters_->fill_u32(0);
  gradients_->fill_u32(0);
}

Mlp::Workspace::Workspace(const Mlp& mlp, std::uint32_t batch) : batch_(batch) {
  gpu::Context& ctx = mlp.context_;
  const std::uint64_t widest = std::uint64_t(mlp.config_.max_width()) * batch * 4;
  if (widest > ctx.info().limits.max_storage_buffer_range)
    throw InputError("mlp batch of " + std::to_string(batch) + " samples needs " + std::to_string(widest) +
                     " bytes per layer, over the device's binding range; train with smaller batches");
  for (const LayerShape& l : mlp.layers_) {
    y_.push_back(std::make_unique<gpu::Buffer<float>>(ctx, std::uint64_t(l.out) * batch, "mlp activations"));
    z_.push_back(l.activation.type == Activation::Sine
                     ? std::make_unique<gpu::Buffer<float>>(ctx, std::uint64_t(l.out) * batch, "mlp pre-activations")
                     : nullptr);
  }
  grad_a_ = std::make_unique<gpu::Buffer<float>>(ctx, std::uint64_t(mlp.config_.max_width()) * batch, "mlp grad a");
  grad_b_ = std::make_unique<gpu::Buffer<float>>(ctx, std::uint64_t(mlp.config_.max_width()) * batch, "mlp grad b");
  std::uint64_t most = 0;
  for (const LayerShape& l : mlp.layers_) most = std::max(most, layer_parameters(l));
  const std::uint64_t slabs = (std::uint64_t(batch) + kSlab - 1) / kSlab;
  partials_ = std::make_unique<gpu::Buffer<float>>(ctx, std::max<std::uint64_t>(1, slabs) * most, "mlp partial grads");
}

void Mlp::record_layer_forward(gpu::Stream& stream, const LayerShape& l, gpu::BufferRange x, gpu::BufferRange y,
                               gpu::BufferRange z, std::uint32_t batch, bool input_sample_major,
                               bool output_sample_major) const {
  const gpu::Kernel& k = context_.kernel(std::string("nn/mlp_forward:") + kBlocking, {{0, kWorkgroup}});
  const ForwardPush push{batch,
                         l.in,
                         l.out,
                         std::uint32_t(l.weight_offset),
                         std::uint32_t(l.bias_offset),
                         std::uint32_t(l.activation.type),
                         l.activation.beta,
                         l.activation.omega,
                         z.size ? 1u : 0u,
                         input_sample_major ? 1u : 0u,
                         output_sample_major ? 1u : 0u};
  stream.dispatch(k, {x, parameters_->whole(), y, z}, push, sample_groups(batch));
}

void Mlp::forward(gpu::Stream& stream, Workspace& ws, gpu::BufferRange input) const {
  if (input.size / 4 < std::uint64_t(config_.input_dim) * ws.batch_)
    throw InternalError("mlp forward: input smaller than input_dim x batch");
  gpu::BufferRange x = input;
  for (std::size_t li = 0; li < layers_.size(); ++li) {
    const gpu::BufferRange z = ws.z_[li] ? ws.z_[li]->whole() : gpu::BufferRange{};
    record_layer_forward(stream, layers_[li], x, ws.y_[li]->whole(), z, ws.batch_, false, false);
    x = ws.y_[li]->whole();
  }
}

void Mlp::backward(gpu::Stream& stream, Workspace& ws, gpu::BufferRange input, gpu::BufferRange grad_output,
                   gpu::BufferRange grad_input, bool accumulate, bool grad_input_sample_major) {
  const std::uint32_t batch = ws.batch_;
  const gpu::Kernel& act = context_.kernel("nn/mlp_activation_backward", {{0, 256}});
  const gpu::Kernel& data = context_.kernel(std::string("nn/mlp_backward_data:") + kBlocking, {{0, kWorkgroup}});
  const gpu::Kernel& weights = context_.kernel("nn/mlp_backward_weights", {{0, kWorkgroup}, {1, kSlabItems}});
  const gpu::Kernel& reduce = context_.kernel("nn/mlp_reduce_partials", {{0, 256}});
  const std::uint32_t slabs = (batch + kSlab - 1) / kSlab;
  gpu::BufferRange grad_y = grad_output;
  gpu::Buffer<float>* dz_buffers[2] = {ws.grad_a_.get(), ws.grad_b_.get()};
  for (std::size_t li = layers_.size(); li-- > 0;) {
    const LayerShape& l = layers_[li];
    const std::uint64_t count = std::uint64_t(l.out) * batch;
    const gpu::BufferRange dz = dz_buffers[li % 2]->range(0, count);
    const gpu::BufferRange z = ws.z_[li] ? ws.z_[li]->whole() : gpu::BufferRange{};
    stream.dispatch(act, {grad_y, ws.y_[li]->whole(), z, dz},
                    ActivationBackwardPush{std::uint32_t(count), std::uint32_t(l.activation.type), l.activation.beta,
                                           l.activation.omega},
                    gpu::Elements(count));
    const gpu::BufferRange x = li == 0 ? input : ws.y_[li - 1]->whole();
    if (batch > 0) {
      const std::uint32_t blocks = ((l.out + 3) / 4) * ((l.in + 1 + 3) / 4);
      const std::uint32_t per_group = std::max(1u, (blocks + 31) / 32);
      stream.dispatch_groups(weights, {dz, x, ws.partials_->whole()},
                             BackwardWeightsPush{batch, l.in, l.out, per_group},
                             gpu::Elements(slabs, (blocks + per_group - 1) / per_group));
      const std::uint64_t params = layer_parameters(l);
      stream.dispatch(reduce, {ws.partials_->whole(), gradients_->whole()},
                      ReducePartialsPush{l.out * l.in, l.out, slabs, std::uint32_t(l.weight_offset), accumulate ? 1u : 0u},
                      gpu::Elements(params));
    }
    const bool first = li == 0;
    if (first && grad_input.size == 0) break;
    const gpu::BufferRange dx = first ? grad_input : dz_buffers[(li + 1) % 2]->range(0, std::uint64_t(l.in) * batch);
    stream.dispatch(data, {dz, parameters_->whole(), dx},
                    BackwardDataPush{batch, l.in, l.out, std::uint32_t(l.weight_offset),
                                     first && grad_input_sample_major ? 1u : 0u, 0u},
                    sample_groups(batch));
    grad_y = dx;
  }
}

void Mlp::infer(gpu::Stream& stream, gpu::BufferRange input, gpu::BufferRange output, std::uint64_t batch) const {
  if (batch == 0) return;
  if (input.size / 4 < batch * config_.input_dim || output.size / 4 < batch * config_.output_dim)
    throw InternalError("mlp infer: input or output smaller than batch rows");
  const std::uint64_t width = config_.max_width();
  const std::uint64_t chunk = std::min<std::uint64_t>(
      {batch, kMaxInferenceChunk,
       gpu::items_per_chunk(context_, {std::uint64_t(config_.input_dim) * 4, std::uint64_t(config_.output_dim) * 4, width * 4})});
  const gpu::BufferRange a = stream.scratch(width * chunk * 4, "mlp inference a");
  const gpu::BufferRange b = stream.scratch(width * chunk * 4, "mlp inference b");
  for (std::uint64_t first = 0; first < batch; first += chunk) {
    const std::uint32_t n = std::uint32_t(std::min(chunk, batch - first));
    gpu::BufferRange x = gpu::sub_range(input, 4, first * config_.input_dim, std::uint64_t(n) * config_.input_dim);
    for (std::size_t li = 0; li < layers_.size(); ++li) {
      const bool last = li + 1 == layers_.size();
      const gpu::BufferRange y = last ? gpu::sub_range(output, 4, first * config_.output_dim, std::uint64_t(n) * config_.output_dim)
                                      : gpu::sub_range(li % 2 ? b : a, 4, 0, std::uint64_t(layers_[li].out) * n);
      record_layer_forward(stream, layers_[li], x, y, {}, n, li == 0, last);
      x = y;
    }
  }
}

double Mlp::forward_flops_per_sample() const {
  double f = 0;
  for (const LayerShape& l : layers_) f += 2.0 * l.in * l.out;
  return f;
}

double Mlp::backward_flops_per_sample() const {
  double f = 0;
  for (std::size_t i = 0; i < layers_.size(); ++i)
    f += 2.0 * layers_[i].in * layers_[i].out * (i == 0 ? 1.0 : 2.0);  // weights, plus inputs past layer 0
  return f;
}

}  // namespace nf::nn
