#include "engine/nn/loss.hpp"

#include "engine/core/error.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/gpu/reduce.hpp"

namespace nf::nn {
namespace {
struct MsePush {
  std::uint32_t batch, dims, stride4;
};
}  // namespace

void mse_loss(gpu::Stream& stream, gpu::BufferRange prediction, gpu::BufferRange target, gpu::BufferRange grad,
              gpu::BufferRange loss, std::uint32_t batch, std::uint32_t dims, std::uint32_t stride) {
  gpu::require_bytes(prediction, std::uint64_t(batch) * stride * 4, "mse prediction");
  gpu::require_bytes(grad, std::uint64_t(batch) * stride * 4, "mse gradient");
  gpu::require_bytes(target, std::uint64_t(batch) * dims * 4, "mse target");
  gpu::require_bytes(loss, 4, "mse loss");
  if (stride % 4 || dims > stride)
    throw InternalError("mse loss: row stride " + std::to_string(stride) + " is not a multiple of 4 of at least " +
                        std::to_string(dims) + " columns");
  const std::uint32_t wg = gpu::primitive_workgroup(stream.context(), 256);
  const gpu::Kernel& k = stream.context().kernel("nn/loss_mse", {{0, wg}});
  const std::uint64_t count = std::uint64_t(batch) * stride / 4;  // vec4 per invocation
  if (count == 0) {
    stream.fill(gpu::sub_range(loss, 4, 0, 1), 0);
    return;
  }
  const std::uint64_t groups = std::max<std::uint64_t>(1, (count + wg - 1) / wg);
  const gpu::BufferRange partials = stream.scratch(groups * 4, "loss partials");
  // Just the batch's rows of the prediction: a texel view has its own size limit.
  stream.dispatch(k, {grad, target, partials, gpu::sub_range(prediction, 4, 0, std::uint64_t(batch) * stride)},
                  MsePush{batch, dims, stride / 4}, gpu::Elements(groups * wg));
  gpu::reduce(stream, gpu::ReduceOp::Sum, gpu::ScalarType::F32, partials, gpu::sub_range(loss, 4, 0, 1));
}

}  // namespace nf::nn
