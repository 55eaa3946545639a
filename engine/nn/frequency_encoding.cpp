#include "engine/nn/frequency_encoding.hpp"

#include "engine/core/error.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::nn {
namespace {

struct ForwardPush {
  std::uint32_t batch, dims, frequencies, include_input, out_dim, out4;
};
struct BackwardPush {
  std::uint32_t batch, dims, frequencies, include_input, out_stride, accumulate;
};
constexpr std::uint32_t kWorkgroup = 64;

}  // namespace

FrequencyEncoding::FrequencyEncoding(const FrequencyEncodingConfig& config) : config_(config) {
  if (config.dims < 1 || config.dims > 16) throw InputError("frequency encoding dims must be 1..16");
  if (config.frequencies > 24) throw InputError("frequency encoding frequencies must be at most 24");
}

void FrequencyEncoding::forward(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange encoded,
                                std::uint32_t batch) const {
  gpu::require_bytes(points, std::uint64_t(batch) * config_.dims * 4, "frequency encoding points");
  gpu::require_bytes(encoded, std::uint64_t(batch) * config_.output_stride() * 4, "frequency encoding output");
  const gpu::Kernel& k = stream.context().kernel("nn/frequency_encoding_fwd", {{0, kWorkgroup}});
  const ForwardPush push{batch, config_.dims, config_.frequencies, config_.include_input ? 1u : 0u,
                         config_.output_dim(), config_.output_stride() / 4};
  stream.dispatch(k, {points, encoded}, push, gpu::Elements(batch));
}

void FrequencyEncoding::backward(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange grad_encoded,
                                 gpu::BufferRange grad_points, std::uint32_t batch, bool accumulate) const {
  gpu::require_bytes(points, std::uint64_t(batch) * config_.dims * 4, "frequency encoding points");
  gpu::require_bytes(grad_encoded, std::uint64_t(batch) * config_.output_stride() * 4, "frequency encoding gradient");
  gpu::require_bytes(grad_points, std::uint64_t(batch) * config_.dims * 4, "frequency encoding point gradient");
  const gpu::Kernel& k = stream.context().kernel("nn/frequency_encoding_bwd", {{0, kWorkgroup}});
  const BackwardPush push{batch, config_.dims, config_.frequencies, config_.include_input ? 1u : 0u,
                          config_.output_stride(), accumulate ? 1u : 0u};
  stream.dispatch(k, {points, grad_encoded, grad_points}, push, gpu::Elements(batch));
}

}  // namespace nf::nn
