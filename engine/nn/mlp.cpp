#include "engine/nn/mlp.hpp"

#include <algorithm>
#include <numeric>
#include <span>

#include "engine/core/error.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::nn {
namespace {

constexpr std::uint32_t kWorkgroup = 64;
// mlp_forward's blocks, preferred first: rows x samples per invocation. 32 accumulators fill the
// vector registers of an AVX-512 host. On CPU devices (lavapipe) a uniform load costs a bounds
// check and a branch, so each weight feeds two samples (8 x 4 or 16 x 2 spill; 8 x 2 measured 10 %
// faster than 32 x 1 on the strand decoder); GPUs broadcast weights for free and want one sample
// per invocation. Narrower blocks serve devices with a small uniform range.
// NF_MLP_GPU_BLOCKS=1 takes the GPU blocks on any device, so that CI runs them.
struct ForwardBlock {
  std::uint32_t cols, samples;
};
constexpr ForwardBlock kCpuBlocks[] = {{8, 2}};
constexpr ForwardBlock kGpuBlocks[] = {{32, 1}, {16, 1}, {8, 2}};
// Input vec4 per mlp_forward dispatch: its body is unrolled, and compiling 16 x 32 vec4 already
// takes lavapipe's LLVM 8 s (once per machine: Mesa caches it), twice that 40 s.
constexpr std::uint32_t kInputChunk4 = 16;
constexpr std::uint32_t kWeightWindow4 = 4096;  // mlp_forward's uniform weight window (64 KiB)
// mlp_backward_weights: samples per partial sum (its rows stay in cache while a slab's blocks are
// summed), and input vec4 per block (4 x 4 kWeightBlockK accumulators per lane).
constexpr std::uint32_t kSlab = 512;
constexpr std::uint32_t kWeightBlockK = 2;
constexpr std::uint32_t kMaxInferenceChunk = 1u << 16;
// Hidden activations and gradients are lane-interleaved in groups of this many samples
// (shaders/include/nf_rows.glsl); tensors crossing the module's boundary stay sample-major.
constexpr std::uint32_t kRowGroup = 8;
std::uint64_t interleaved_rows(std::uint64_t batch) { return (batch + kRowGroup - 1) / kRowGroup * kRowGroup; }

struct ForwardPush {
  std::uint32_t batch, out4, out_dim, row_first, rows;
  float beta, omega;
  std::uint32_t has_bias, accumulate, w_base, stride4, x_first4, x_interleaved, y_interleaved;
};
struct ActivationBackwardPush {
  std::uint32_t count4, batch, out_dim, out4;
  float beta, omega;
  std::uint32_t grad_z_interleaved, grad_y_interleaved, y_interleaved;
};
struct TransposePush {
  std::uint32_t in_dim, in_stride, out_dim, out_stride, weight_offset;
};
struct BackwardWeightsPush {
  std::uint32_t batch, in4, out4, out_dim, k_blocks, blocks, dz_interleaved, x_interleaved;
};
struct ReducePartialsPush {
  std::uint32_t weights, biases, slabs, weight_offset, bias_offset, accumulate;
};

std::uint64_t layer_parameters(const LayerShape& l) { return std::uint64_t(l.out) * l.in_stride + l.out; }

}  // namespace

Mlp::Mlp(gpu::Context& context, const MlpConfig& config, const std::string& name)
    : context_(context), config_(config), gpu_blocks_(gpu::use_gpu_layout(context, "NF_MLP_GPU_BLOCKS")) {
  config_.validate();
  layers_ = config_.layers();
  for (const LayerShape& l : layers_) {
    block_for(l.in_stride);  // throws if the device's uniform buffers cannot hold a row block
    block_for(l.out_stride);
  }
  parameters_ = std::make_unique<gpu::Buffer<float>>(context, config_.parameter_count(), name + " parameters");
  gradients_ = std::make_unique<gpu::Buffer<float>>(context, config_.parameter_count(), name + " gradients");
  parameters_->fill_u32(0);
  gradients_->fill_u32(0);
}

std::uint64_t Mlp::weight_window4() const {
  return std::min<std::uint64_t>(kWeightWindow4, context_.info().limits.max_uniform_buffer_range / 16);
}

Mlp::Block Mlp::block_for(std::uint32_t in_stride) const {
  // mlp_forward's weight window: COLS rows of in_stride floats plus 16 vec4 of alignment slack.
  const std::uint64_t capacity = weight_window4();
  const std::span<const ForwardBlock> blocks =
      gpu_blocks_ ? std::span<const ForwardBlock>(kGpuBlocks) : std::span<const ForwardBlock>(kCpuBlocks);
  for (const ForwardBlock& b : blocks)
    if (std::uint64_t(b.cols) * (in_stride / 4) + 16 <= capacity) return {b.cols, b.samples};
  throw DeviceError("mlp: a layer with " + std::to_string(in_stride) + " inputs needs more uniform-buffer range than "
                    "the device's " + std::to_string(context_.info().limits.max_uniform_buffer_range) + " bytes");
}

void Mlp::record_product(gpu::Stream& stream, const Product& p, gpu::BufferRange x, gpu::BufferRange y,
                         gpu::BufferRange z, std::uint32_t batch, Layouts layouts) const {
  const Block block = block_for(p.in_stride);
  const std::uint32_t cols = block.cols, in4 = p.in_stride / 4;
  const std::string variant = "nn/mlp_forward:c" + std::to_string(cols) + "s" + std::to_string(block.samples);
  const std::uint64_t align = std::max<std::uint64_t>(4, context_.info().limits.min_uniform_buffer_offset_alignment / 4);
  const std::uint64_t buffer_floats = p.weights->bytes() / 4;
  // Each group of kRowGroup invocations takes kRowGroup x samples neighbouring samples.
  const std::uint64_t per_group = std::uint64_t(kRowGroup) * block.samples;
  const std::uint64_t invocations = (std::uint64_t(batch) + per_group - 1) / per_group * kRowGroup;
  for (std::uint32_t first = 0; first < p.out_dim; first += cols) {
    const std::uint32_t rows = std::min(cols, p.out_dim - first);
    for (std::uint32_t k4 = 0; k4 < in4; k4 += kInputChunk4) {
      const std::uint32_t chunk4 = std::min(kInputChunk4, in4 - k4);
      const bool first_chunk = k4 == 0, last_chunk = k4 + chunk4 == in4;
      const bool store_z = last_chunk && z.size;
      const gpu::Kernel& k = context_.kernel(
          variant, {{0, kWorkgroup},
                    {3, chunk4},
                    {4, std::uint32_t(last_chunk ? p.activation.type : Activation::None)},
                    {5, store_z ? 1u : 0u}});
      // Bind from an aligned offset at or before the block; the shader skips the difference.
      const std::uint64_t start = p.weight_offset + std::uint64_t(first) * p.in_stride + 4u * k4;
      const std::uint64_t base = start / align * align;
      const std::uint64_t window = std::min<std::uint64_t>(weight_window4() * 4, buffer_floats - base);
      const ForwardPush push{batch,
                             p.out_stride / 4,
                             p.out_dim,
                             first,
                             rows,
                             p.activation.beta,
                             p.activation.omega,
                             first_chunk && p.biases.size ? 1u : 0u,
                             first_chunk ? 0u : 1u,
                             std::uint32_t((start - base) / 4),
                             in4,
                             k4,
                             layouts.x_interleaved,
                             layouts.y_interleaved};
      stream.dispatch(k, {y, store_z ? z : gpu::BufferRange{}, p.weights->range_bytes(base * 4, window * 4), p.biases, x},
                      push, gpu::Elements(invocations));
    }
  }
}

void Mlp::record_layer_forward(gpu::Stream& stream, const LayerShape& l, gpu::BufferRange x, gpu::BufferRange y,
                               gpu::BufferRange z, std::uint32_t batch, Layouts layouts) const {
  const Product p{parameters_.get(), l.weight_offset, l.in_stride, l.out, l.out_stride,
                  parameters_->range(l.bias_offset, l.out), l.activation};
  record_product(stream, p, x, y, z, batch, layouts);
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
  std::uint64_t most = 0;
  for (const LayerShape& l : mlp.layers_) most = std::max(most, layer_parameters(l));
  const std::uint64_t slabs = std::max<std::uint64_t>(1, (std::uint64_t(batch) + kSlab - 1) / kSlab);
  if (slabs * most * 4 > lim.max_storage_buffer_range)
    throw InputError("mlp batch of " + std::to_string(batch) + " samples needs " + std::to_string(slabs * most * 4) +
                     " bytes of per-slab weight-gradient partials, over the device's binding range; train with "
                     "smaller batches");
  partials_ = std::make_unique<gpu::Buffer<float>>(ctx, slabs * most, "mlp partial grads");
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
  const gpu::Kernel& transpose = context_.kernel("nn/mlp_transpose", {{0, 256}});
  const gpu::Kernel& reduce = context_.kernel("nn/mlp_reduce_partials", {{0, 256}});
  const std::uint32_t slabs = (batch + kSlab - 1) / kSlab;
  gpu::BufferRange grad_y = grad_output;
  gpu::Buffer<float>* buffers[2] = {ws.grad_a_.get(), ws.grad_b_.get()};
  for (std::size_t li = layers_.size(); li-- > 0;) {
    const LayerShape& l = layers_[li];
    const bool last = li + 1 == layers_.size();
    const std::uint64_t count = std::uint64_t(l.out_stride) * interleaved_rows(batch);
    const gpu::BufferRange dz = buffers[li % 2]->range(0, count);  // interleaved
    const gpu::BufferRange z = ws.z_[li] ? ws.z_[li]->whole() : gpu::BufferRange{};
    const gpu::Kernel& act =
        context_.kernel("nn/mlp_activation_backward", {{0, 256}, {1, std::uint32_t(l.activation.type)}});
    stream.dispatch(act, {dz, grad_y, ws.y_[li]->whole(), z},
                    ActivationBackwardPush{std::uint32_t(count / 4), batch, l.out, l.out_stride / 4, l.activation.beta,
                                           l.activation.omega, 1u, last ? 0u : 1u, last ? 0u : 1u},
                    gpu::Elements(count / 4));
    const gpu::BufferRange x = li == 0 ? input : ws.y_[li - 1]->whole();
    const gpu::Kernel& weights =
        context_.kernel("nn/mlp_backward_weights", {{0, kWorkgroup}, {1, kSlab}, {2, kWeightBlockK}});
    const std::uint32_t k_blocks = (l.in_stride / 4 + 1 + kWeightBlockK - 1) / kWeightBlockK;
    const std::uint32_t blocks = slabs * k_blocks * (l.out_stride / 4);
    stream.dispatch(weights, {ws.partials_->whole(), dz, x},
                    BackwardWeightsPush{batch, l.in_stride / 4, l.out_stride / 4, l.out, k_blocks, blocks, 1u,
                                        li > 0 ? 1u : 0u},
                    gpu::Elements(blocks));
    stream.dispatch(reduce, {ws.partials_->whole(), gradients_->whole()},
                    ReducePartialsPush{l.out * l.in_stride, l.out, slabs, std::uint32_t(l.weight_offset),
                                       std::uint32_t(l.bias_offset), accumulate ? 1u : 0u},
                    gpu::Elements(layer_parameters(l)));
    if (li == 0 && grad_input.size == 0) break;
    // dx = W^T dz: the forward kernel on the transposed weights.
    const std::uint64_t transposed = std::uint64_t(l.in) * l.out_stride;
    stream.dispatch(transpose, {parameters_->whole(), ws.transposed_->range(0, transposed)},
                    TransposePush{l.in, l.in_stride, l.out, l.out_stride, std::uint32_t(l.weight_offset)},
                    gpu::Elements(transposed));
    const gpu::BufferRange dx =
        li == 0 ? grad_input : buffers[(li + 1) % 2]->range(0, std::uint64_t(l.in_stride) * interleaved_rows(batch));
    const Product p{ws.transposed_.get(), 0, l.out_stride, l.in, l.in_stride, {}, {Activation::None}};
    record_product(stream, p, dz, dx, {}, batch, {1u, li > 0 ? 1u : 0u});
    grad_y = dx;
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
