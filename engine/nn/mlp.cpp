#include "engine/nn/mlp.hpp"

#include <algorithm>

#include "engine/core/error.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::nn {
namespace {

// mlp_fwd: output rows per workgroup block (32 accumulators per lane, its c32s1 variant) and
// samples per workgroup at most (a larger workgroup spreads the staging of its weights over more
// samples; 512 measured the same as 256 on lavapipe).
constexpr std::uint32_t kForwardCols = 32;
constexpr std::uint32_t kMaxForwardGroup = 256;
// Input vec4 per mlp_fwd dispatch at most: a 256-wide layer in one (its body is unrolled).
constexpr std::uint32_t kMaxInputChunk4 = 64;
// mlp_weights_bwd: inputs per block (accumulators per lane, its COLS) and samples per slab at
// most (a slab's block of inputs is staged in shared memory, 16 bytes per 4 inputs of a sample).
constexpr std::uint32_t kWeightCols = 32;
constexpr std::uint32_t kMaxSlab4 = 64;
// Outputs (lanes) per mlp_weights_bwd workgroup at most: enough to spread the staging of a
// slab (4 % of the work at 256), few enough for any GPU.
constexpr std::uint32_t kMaxWeightGroup = 256;
constexpr std::uint32_t kMaxInferenceChunk = 1u << 16;
// Hidden activations and gradients are lane-interleaved in groups of this many samples
// (shaders/include/nf_rows.glsl); tensors crossing the module's boundary stay sample-major.
constexpr std::uint32_t kRowGroup = 8;
std::uint64_t interleaved_rows(std::uint64_t batch) { return (batch + kRowGroup - 1) / kRowGroup * kRowGroup; }

struct ForwardPush {
  std::uint32_t batch, out4, out_dim, blocks;
  float beta, omega;
  std::uint32_t has_bias, accumulate, w_base, stride4, x_first4, x_interleaved, y_interleaved, zt_stride;
};
struct ActivationBackwardPush {
  std::uint32_t quads, batch, out_dim, out4;
  float beta, omega;
  std::uint32_t zt_stride4;
};
struct TransposePush {
  std::uint32_t in_dim, in_stride, out_dim, out_stride, weight_offset;
};
struct BackwardWeightsPush {
  std::uint32_t batch, in4, out_dim, dzt_stride4, o_groups, i_blocks, groups, x_interleaved;
};
struct ReducePartialsPush {
  std::uint32_t weights, biases, slabs, weight_offset, bias_offset, accumulate, slab_stride4;
};

// Floats between mlp_weights_bwd' slab copies of a layer's gradient: whole vec4.
std::uint64_t slab_stride(const LayerShape& l) { return std::uint64_t(l.out) * l.in_stride + (l.out + 3) / 4 * 4; }

}  // namespace

Mlp::Mlp(gpu::Context& context, const MlpConfig& config, const std::string& name)
    : context_(context), config_(config) {
  config_.validate();
  layers_ = config_.layers();
  if (forward_chunk4() == 0)
    throw DeviceError("mlp: the device's " + std::to_string(context_.info().limits.max_compute_shared_memory) +
                      " bytes of shared memory cannot hold a block of " + std::to_string(kForwardCols) +
                      " weight rows");
  // mlp_fwd reads a layer's weights, and the input adjoint their transpose, as one texel view.
  const std::uint64_t texels = context_.info().limits.max_texel_buffer_elements;
  for (std::size_t li = 0; li < layers_.size(); ++li) {
    const LayerShape& l = layers_[li];
    const std::uint64_t needed = std::max(std::uint64_t(l.out) * l.in_stride, std::uint64_t(l.in) * l.out_stride) / 4;
    if (needed > texels)
      throw DeviceError("mlp layer " + std::to_string(li) + " (" + std::to_string(l.in) + " -> " +
                        std::to_string(l.out) + ") needs " + std::to_string(needed) +
                        " texels of weights, more than the device's maxTexelBufferElements " + std::to_string(texels));
  }
  parameters_ = std::make_unique<gpu::Buffer<float>>(context, config_.parameter_count(), name + " parameters");
  gradients_ = std::make_unique<gpu::Buffer<float>>(context, config_.parameter_count(), name + " gradients");
  parameters_->fill_u32(0);
  gradients_->fill_u32(0);
}

std::uint32_t Mlp::workgroup_limit(std::uint32_t most) const {
  // Whole groups of kRowGroup lanes (the interleaved layout's sample groups).
  const gpu::DeviceLimits& lim = context_.info().limits;
  const std::uint32_t limit = std::min({most, lim.max_workgroup_invocations, lim.max_workgroup_size[0]});
  return std::max(kRowGroup, limit / kRowGroup * kRowGroup);
}

std::uint32_t Mlp::slab4() const {
  return std::min(kMaxSlab4, context_.info().limits.max_compute_shared_memory / (16 * kWeightCols));
}

std::uint32_t Mlp::slabs(std::uint32_t batch) const {
  return std::max<std::uint32_t>(1, (batch + 4 * slab4() - 1) / (4 * slab4()));
}

std::uint32_t Mlp::forward_chunk4() const {
  // mlp_fwd stages kForwardCols rows of the chunk's inputs (16 bytes per vec4) in shared memory.
  return std::min(kMaxInputChunk4, context_.info().limits.max_compute_shared_memory / (16 * kForwardCols));
}

void Mlp::record_product(gpu::Stream& stream, const Product& p, gpu::BufferRange x, gpu::BufferRange y,
                         gpu::BufferRange z, std::uint32_t batch, Layouts layouts,
                         const AdjointEpilogue& adjoint) const {
  const std::uint32_t in4 = p.in_stride / 4, most4 = forward_chunk4();
  const std::uint32_t blocks = (p.out_dim + kForwardCols - 1) / kForwardCols;
  const std::uint32_t group_size = workgroup_limit(kMaxForwardGroup);
  const std::uint64_t tiles = (std::uint64_t(batch) + group_size - 1) / group_size;
  // The weights as texels, bound from an aligned offset at or before row 0 (layers start on
  // kLayerAlignment floats, so the difference is 0 on devices that align to 256 bytes or less).
  const std::uint64_t align = std::max<std::uint64_t>(4, context_.info().limits.min_texel_buffer_offset_alignment / 4);
  const std::uint64_t base = p.weight_offset / align * align;
  const gpu::BufferRange w =
      p.weights->range_bytes(base * 4, (p.weight_offset - base + std::uint64_t(p.out_dim) * p.in_stride) * 4);
  for (std::uint32_t k4 = 0; k4 < in4; k4 += most4) {
    const std::uint32_t chunk4 = std::min(most4, in4 - k4);
    const bool first_chunk = k4 == 0, last_chunk = k4 + chunk4 == in4;
    const bool store_z = last_chunk && z.size, epilogue = last_chunk && adjoint.below.size;
    const gpu::Kernel& k = context_.kernel("nn/mlp_fwd:c32s1",
                                           {{0, group_size},
                                            {3, chunk4},
                                            {4, std::uint32_t(last_chunk ? p.activation.type : Activation::None)},
                                            {5, store_z ? 1u : 0u},
                                            {6, epilogue ? 1u : 0u},
                                            {7, std::uint32_t(adjoint.activation.type)}});
    const ActivationSpec& a = adjoint.below.size ? adjoint.activation : p.activation;
    const ForwardPush push{batch,
                           p.out_stride / 4,
                           p.out_dim,
                           blocks,
                           a.beta,
                           a.omega,
                           first_chunk && p.biases.size ? 1u : 0u,
                           first_chunk ? 0u : 1u,
                           std::uint32_t((p.weight_offset - base) / 4),
                           in4,
                           k4,
                           layouts.x_interleaved,
                           layouts.y_interleaved,
                           adjoint.zt_stride};
    stream.dispatch(k,
                    {y, store_z ? z : gpu::BufferRange{}, epilogue ? adjoint.transposed : gpu::BufferRange{},
                     p.biases, x, w, epilogue ? adjoint.below : gpu::BufferRange{}},
                    push, gpu::Elements(blocks * tiles * group_size));
  }
}

void Mlp::record_layer_forward(gpu::Stream& stream, const LayerShape& l, gpu::BufferRange x, gpu::BufferRange y,
                               gpu::BufferRange z, std::uint32_t batch, Layouts layouts) const {
  const Product p{parameters_.get(), l.weight_offset, l.in_stride, l.out, l.out_stride,
                  parameters_->range(l.bias_offset, l.out), l.activation};
  record_product(stream, p, x, y, z, batch, layouts, AdjointEpilogue{});
}

Mlp::Workspace::Workspace(const Mlp& mlp, std::uint32_t batch) : batch_(batch) {
  gpu::Context& ctx = mlp.context_;
  std::uint32_t widest = 0;
  std::uint64_t largest_transpose = 1;
  for (const LayerShape& l : mlp.layers_) {
    widest = std::max({widest, l.in_stride, l.out_stride});
    largest_transpose = std::max<std::uint64_t>(largest_transpose, std::uint64_t(l.in) * l.out_stride);
  }
  const std::uint64_t bytes = std::uint64_t(widest) * interleaved_rows(batch) * 4;
  const gpu::DeviceLimits& lim = ctx.info().limits;
  if (bytes > lim.max_storage_buffer_range || bytes / 16 > lim.max_texel_buffer_elements)
    throw InputError("mlp batch of " + std::to_string(batch) + " samples needs " + std::to_string(bytes) +
                     " bytes per layer, over the device's binding range; train with smaller batches");
  const std::uint64_t rows = interleaved_rows(batch);
  for (std::size_t li = 0; li < mlp.layers_.size(); ++li) {
    const LayerShape& l = mlp.layers_[li];
    // Hidden layers interleaved (padded to a whole group), the output sample-major.
    const std::uint64_t floats = std::uint64_t(l.out_stride) * (li + 1 < mlp.layers_.size() ? rows : batch);
    y_.push_back(std::make_unique<gpu::Buffer<float>>(ctx, floats, "mlp activations"));
    z_.push_back(l.activation.type == Activation::Sine
                     ? std::make_unique<gpu::Buffer<float>>(ctx, floats, "mlp pre-activations")
                     : nullptr);
  }
  grad_a_ = std::make_unique<gpu::Buffer<float>>(ctx, std::uint64_t(widest) * rows, "mlp grad a");
  grad_b_ = std::make_unique<gpu::Buffer<float>>(ctx, std::uint64_t(widest) * rows, "mlp grad b");
  transposed_ = std::make_unique<gpu::Buffer<float>>(ctx, largest_transpose, "mlp transposed weights");
  // The weight gradient's slab copies and the transposed output gradient, whole slabs long.
  std::uint64_t most = 0;
  std::uint32_t widest_out = 0;
  for (const LayerShape& l : mlp.layers_) {
    most = std::max(most, slab_stride(l));
    widest_out = std::max(widest_out, l.out);
  }
  const std::uint64_t slabs = mlp.slabs(batch), padded = slabs * 4 * mlp.slab4();
  if (slabs * most * 4 > lim.max_storage_buffer_range || slabs * most / 4 > lim.max_texel_buffer_elements ||
      widest_out * padded * 4 > lim.max_storage_buffer_range || widest_out * padded / 4 > lim.max_texel_buffer_elements)
    throw InputError("mlp batch of " + std::to_string(batch) + " samples needs " +
                     std::to_string(std::max(slabs * most, widest_out * padded) * 4) +
                     " bytes of weight-gradient partials or transposed gradients, over the device's binding range; "
                     "train with smaller batches");
  partials_ = std::make_unique<gpu::Buffer<float>>(ctx, slabs * most, "mlp partial grads");
  grad_zt_ = std::make_unique<gpu::Buffer<float>>(ctx, widest_out * padded, "mlp transposed grad z");
}

void Mlp::forward(gpu::Stream& stream, Workspace& ws, gpu::BufferRange input) const {
  gpu::require_bytes(input, std::uint64_t(input_stride()) * ws.batch_ * 4, "mlp forward input");
  // Bind just the batch's rows: they are read as a texel buffer, whose range has its own limit.
  gpu::BufferRange x = gpu::sub_range(input, 4, 0, std::uint64_t(input_stride()) * ws.batch_);
  for (std::size_t li = 0; li < layers_.size(); ++li) {
    const gpu::BufferRange z = ws.z_[li] ? ws.z_[li]->whole() : gpu::BufferRange{};
    record_layer_forward(stream, layers_[li], x, ws.y_[li]->whole(), z, ws.batch_,
                         {li > 0 ? 1u : 0u, li + 1 < layers_.size() ? 1u : 0u});
    x = ws.y_[li]->whole();
  }
}

void Mlp::backward(gpu::Stream& stream, Workspace& ws, gpu::BufferRange input, gpu::BufferRange grad_output,
                   gpu::BufferRange grad_input, bool accumulate) {
  const std::uint32_t batch = ws.batch_;
  if (batch == 0) return;
  gpu::require_bytes(input, std::uint64_t(batch) * input_stride() * 4, "mlp backward input");
  gpu::require_bytes(grad_output, std::uint64_t(batch) * output_stride() * 4, "mlp output gradient");
  if (grad_input.size) gpu::require_bytes(grad_input, std::uint64_t(batch) * input_stride() * 4, "mlp input gradient");
  // Just the batch's rows of the caller's tensors (texel ranges have their own limit).
  input = gpu::sub_range(input, 4, 0, std::uint64_t(batch) * input_stride());
  grad_output = gpu::sub_range(grad_output, 4, 0, std::uint64_t(batch) * output_stride());
  if (grad_input.size) grad_input = gpu::sub_range(grad_input, 4, 0, std::uint64_t(batch) * input_stride());
  const gpu::Kernel& transpose = context_.kernel("nn/mlp_transpose", {{0, workgroup_limit(256)}});
  const gpu::Kernel& reduce = context_.kernel("nn/mlp_reduce_partials", {{0, workgroup_limit(256)}});
  const std::uint32_t slab_count = slabs(batch), zt_stride = slab_count * 4 * slab4();
  const std::uint32_t widest_group = workgroup_limit(kMaxWeightGroup);
  gpu::Buffer<float>* buffers[2] = {ws.grad_a_.get(), ws.grad_b_.get()};
  for (std::size_t li = layers_.size(); li-- > 0;) {
    const LayerShape& l = layers_[li];
    const bool last = li + 1 == layers_.size();
    const std::uint64_t count = std::uint64_t(l.out_stride) * interleaved_rows(batch);
    const gpu::BufferRange dz = buffers[li % 2]->range(0, count);  // interleaved
    const gpu::BufferRange dzt = ws.grad_zt_->range(0, std::uint64_t(l.out) * zt_stride);
    if (last) {  // below the top layer, the input adjoint above has written dz and dz^T
      const gpu::Kernel& act = context_.kernel("nn/mlp_activation_bwd",
                                               {{0, workgroup_limit(256)}, {1, std::uint32_t(l.activation.type)}});
      stream.dispatch(act, {dz, dzt, grad_output, ws.kept(li)},
                      ActivationBackwardPush{std::uint32_t(interleaved_rows(batch) / 4), batch, l.out,
                                             l.out_stride / 4, l.activation.beta, l.activation.omega, zt_stride / 4},
                      gpu::Elements(count / 16));
    }
    const gpu::BufferRange x = li == 0 ? input : ws.y_[li - 1]->whole();
    // One lane per output: as few workgroups across the outputs as the device allows, evened out.
    const std::uint32_t o_groups = (l.out + widest_group - 1) / widest_group;
    const std::uint32_t group_size = ((l.out + o_groups - 1) / o_groups + kRowGroup - 1) / kRowGroup * kRowGroup;
    const gpu::Kernel& weights = context_.kernel("nn/mlp_weights_bwd", {{0, group_size}, {1, slab4()}});
    const std::uint32_t i_blocks = (l.in_stride + kWeightCols - 1) / kWeightCols;
    const std::uint32_t groups = o_groups * i_blocks * slab_count;
    stream.dispatch(weights, {ws.partials_->whole(), dzt, x},
                    BackwardWeightsPush{batch, l.in_stride / 4, l.out, zt_stride / 4, o_groups, i_blocks, groups,
                                        li > 0 ? 1u : 0u},
                    gpu::Elements(std::uint64_t(groups) * group_size));
    stream.dispatch(reduce, {gradients_->whole(), ws.partials_->range(0, slab_count * slab_stride(l))},
                    ReducePartialsPush{l.out * l.in_stride, l.out, slab_count, std::uint32_t(l.weight_offset),
                                       std::uint32_t(l.bias_offset), accumulate ? 1u : 0u,
                                       std::uint32_t(slab_stride(l) / 4)},
                    gpu::Elements(slab_stride(l) / 4));
    if (li == 0 && grad_input.size == 0) break;
    // dx = W^T dz: the forward kernel on the transposed weights.
    const std::uint64_t transposed = std::uint64_t(l.in) * l.out_stride;
    stream.dispatch(transpose, {parameters_->whole(), ws.transposed_->range(0, transposed)},
                    TransposePush{l.in, l.in_stride, l.out, l.out_stride, std::uint32_t(l.weight_offset)},
                    gpu::Elements(transposed));
    const gpu::BufferRange dx =
        li == 0 ? grad_input : buffers[(li + 1) % 2]->range(0, std::uint64_t(l.in_stride) * interleaved_rows(batch));
    const Product p{ws.transposed_.get(), 0, l.out_stride, l.in, l.in_stride, {}, {Activation::None}};
    AdjointEpilogue below;  // a hidden layer below: its dz and dz^T straight from this product
    if (li > 0) {
      const LayerShape& b = layers_[li - 1];
      below.below = ws.kept(li - 1);
      below.activation = b.activation;
      below.transposed = ws.grad_zt_->range(0, std::uint64_t(b.out) * zt_stride);
      below.zt_stride = zt_stride;
    }
    record_product(stream, p, dz, dx, {}, batch, {1u, li > 0 ? 1u : 0u}, below);
  }
}

void Mlp::infer(gpu::Stream& stream, gpu::BufferRange input, gpu::BufferRange output, std::uint64_t batch) const {
  if (batch == 0) return;
  if (input.size / 4 < batch * input_stride() || output.size / 4 < batch * output_stride())
    throw InternalError("mlp infer: input or output smaller than batch rows");
  std::uint64_t widest = 0;
  for (const LayerShape& l : layers_) widest = std::max<std::uint64_t>({widest, l.in_stride, l.out_stride});
  const gpu::DeviceLimits& lim = context_.info().limits;
  const std::uint64_t fits = std::min(
      gpu::items_per_chunk(context_, {std::uint64_t(input_stride()) * 4, std::uint64_t(output_stride()) * 4, widest * 4}),
      lim.max_texel_buffer_elements * 16 / (widest * 4));
  std::uint64_t chunk = std::min<std::uint64_t>({batch, kMaxInferenceChunk, fits});
  // The interleaved scratch holds whole groups of kRowGroup samples: keep them within a binding,
  // in chunks of a multiple of 64 samples (which keeps them on the offset alignment too).
  if (interleaved_rows(chunk) > fits && chunk >= 64) chunk = chunk / 64 * 64;
  const gpu::BufferRange a = stream.scratch(widest * interleaved_rows(chunk) * 4, "mlp inference a");
  const gpu::BufferRange b = stream.scratch(widest * interleaved_rows(chunk) * 4, "mlp inference b");
  for (std::uint64_t first = 0; first < batch; first += chunk) {
    const std::uint32_t n = std::uint32_t(std::min(chunk, batch - first));
    gpu::BufferRange x = gpu::sub_range(input, 4, first * input_stride(), std::uint64_t(n) * input_stride());
    for (std::size_t li = 0; li < layers_.size(); ++li) {
      const LayerShape& l = layers_[li];
      const bool last = li + 1 == layers_.size();
      const gpu::BufferRange y = last ? gpu::sub_range(output, 4, first * output_stride(), std::uint64_t(n) * output_stride())
                                      : gpu::sub_range(li % 2 ? b : a, 4, 0, std::uint64_t(l.out_stride) * interleaved_rows(n));
      record_layer_forward(stream, l, x, y, {}, n, {li > 0 ? 1u : 0u, last ? 0u : 1u});
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
