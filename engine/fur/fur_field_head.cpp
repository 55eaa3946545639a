#include "engine/fur/fur_field_head.hpp"

#include <algorithm>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::fur {
namespace {

struct Push {
  std::uint32_t strands, latent, in_stride, latent_stride, segments;
};
constexpr std::uint32_t kWorkgroup = 64;

template <class Body>
void for_each_chunk(gpu::Context& context, const FurHeadShape& shape, const Body& body) {
  const std::uint64_t chunk = gpu::items_per_chunk(
      context, {std::uint64_t(shape.in_stride) * 4, std::uint64_t(shape.latent_stride) * 4, std::uint64_t(shape.segments) * 4});
  for (std::uint64_t first = 0; first < shape.strands; first += chunk) body(first, std::min<std::uint64_t>(chunk, shape.strands - first));
}

}  // namespace

void validate(const FurHeadShape& s) {
  if (s.latent < 1) throw InputError("fur field head: the latent needs at least one value");
  if (s.in_stride < s.latent + 1)
    throw InputError("fur field head: MLP rows of " + std::to_string(s.in_stride) + " floats cannot hold a latent of " +
                     std::to_string(s.latent) + " and the confidence");
  if (s.latent_stride < s.latent)
    throw InputError("fur field head: latent rows of " + std::to_string(s.latent_stride) + " floats are below the latent " +
                     std::to_string(s.latent));
  if (s.segments < 1) throw InputError("fur field head: a strand needs at least one segment");
}

void fur_head_forward(gpu::Stream& stream, const FurHeadShape& shape, gpu::BufferRange rows, gpu::BufferRange latents,
                      gpu::BufferRange confidence) {
  validate(shape);
  const std::uint64_t n = shape.strands;
  gpu::require_bytes(rows, n * shape.in_stride * 4, "fur MLP rows");
  gpu::require_bytes(latents, n * shape.latent_stride * 4, "latent rows");
  gpu::require_bytes(confidence, n * shape.segments * 4, "segment confidence");
  gpu::Context& context = stream.context();
  const gpu::Kernel& kernel = context.kernel("fur/fur_field_head_fwd", {{0, kWorkgroup}});
  for_each_chunk(context, shape, [&](std::uint64_t first, std::uint64_t count) {
    const Push push{std::uint32_t(count), shape.latent, shape.in_stride, shape.latent_stride, shape.segments};
    stream.dispatch(kernel,
                    {gpu::sub_range(rows, 4, first * shape.in_stride, count * shape.in_stride),
                     gpu::sub_range(latents, 4, first * shape.latent_stride, count * shape.latent_stride),
                     gpu::sub_range(confidence, 4, first * shape.segments, count * shape.segments)},
                    push, gpu::Elements(count));
  });
}

void fur_head_backward(gpu::Stream& stream, const FurHeadShape& shape, gpu::BufferRange rows, gpu::BufferRange grad_latents,
                       gpu::BufferRange grad_confidence, gpu::BufferRange grad_rows) {
  validate(shape);
  const std::uint64_t n = shape.strands;
  gpu::require_bytes(rows, n * shape.in_stride * 4, "fur MLP rows");
  gpu::require_bytes(grad_latents, n * shape.latent_stride * 4, "latent row gradients");
  gpu::require_bytes(grad_confidence, n * shape.segments * 4, "segment confidence gradients");
  gpu::require_bytes(grad_rows, n * shape.in_stride * 4, "fur MLP row gradients");
  gpu::Context& context = stream.context();
  const gpu::Kernel& kernel = context.kernel("fur/fur_field_head_bwd", {{0, kWorkgroup}});
  for_each_chunk(context, shape, [&](std::uint64_t first, std::uint64_t count) {
    const Push push{std::uint32_t(count), shape.latent, shape.in_stride, shape.latent_stride, shape.segments};
    stream.dispatch(kernel,
                    {gpu::sub_range(rows, 4, first * shape.in_stride, count * shape.in_stride),
                     gpu::sub_range(grad_latents, 4, first * shape.latent_stride, count * shape.latent_stride),
                     gpu::sub_range(grad_confidence, 4, first * shape.segments, count * shape.segments),
                     gpu::sub_range(grad_rows, 4, first * shape.in_stride, count * shape.in_stride)},
                    push, gpu::Elements(count));
  });
}

FurHeadOutputs fur_head(gpu::Context& context, const FurHeadShape& shape, std::span<const float> rows) {
  validate(shape);
  if (rows.size() != std::uint64_t(shape.strands) * shape.in_stride) throw InputError("fur field head: rows do not match the shape");
  require_finite(rows, "fur MLP rows");
  gpu::Buffer<float> d_rows(context, rows, "fur MLP rows");
  gpu::Buffer<float> d_latents(context, std::uint64_t(shape.strands) * shape.latent_stride, "latent rows");
  gpu::Buffer<float> d_conf(context, std::uint64_t(shape.strands) * shape.segments, "segment confidence");
  gpu::Stream stream(context);
  fur_head_forward(stream, shape, d_rows, d_latents, d_conf);
  stream.submit_and_wait();
  return {d_latents.download(), d_conf.download()};
}

std::vector<float> fur_head_gradient(gpu::Context& context, const FurHeadShape& shape, std::span<const float> rows,
                                     std::span<const float> grad_latents, std::span<const float> grad_confidence) {
  validate(shape);
  if (rows.size() != std::uint64_t(shape.strands) * shape.in_stride ||
      grad_latents.size() != std::uint64_t(shape.strands) * shape.latent_stride ||
      grad_confidence.size() != std::uint64_t(shape.strands) * shape.segments)
    throw InputError("fur field head: arrays do not match the shape");
  require_finite(rows, "fur MLP rows");
  require_finite(grad_latents, "latent row gradients");
  require_finite(grad_confidence, "segment confidence gradients");
  gpu::Buffer<float> d_rows(context, rows, "fur MLP rows"), d_gl(context, grad_latents, "latent row gradients"),
      d_gc(context, grad_confidence, "segment confidence gradients");
  gpu::Buffer<float> d_grad(context, rows.size(), "fur MLP row gradients");
  gpu::Stream stream(context);
  fur_head_backward(stream, shape, d_rows, d_gl, d_gc, d_grad);
  stream.submit_and_wait();
  return d_grad.download();
}

}  // namespace nf::fur
