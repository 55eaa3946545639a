#include "engine/splat/segment_gaussian.hpp"

#include <cmath>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::splat {
namespace {

struct ForwardPush {
  std::uint32_t strands, points_per_strand;
  float k2, eps2, delta2;
};
struct BackwardPush {
  std::uint32_t strands, points_per_strand;
  float k2, eps2, delta2;
  std::uint32_t accumulate;
};

constexpr std::uint32_t kWorkgroup = 128;

// Strand chunks small enough that every array binding fits the device's storage-buffer range.
template <class Body>
void for_each_chunk(gpu::Context& context, const StrandShape& shape, const Body& body) {
  const std::uint64_t L = shape.points_per_strand;
  const std::uint64_t chunk = gpu::items_per_chunk(context, {L * 12, (L - 1) * 12, (L - 1) * 24});
  for (std::uint64_t first = 0; first < shape.strands; first += chunk)
    body(first, std::min<std::uint64_t>(chunk, shape.strands - first));
}

}  // namespace

void validate(const StrandShape& shape, const SegmentGaussianParams& params, std::uint64_t point_floats) {
  if (shape.points_per_strand < 2)
    throw InputError("strands: points_per_strand is " + std::to_string(shape.points_per_strand) +
                     "; a strand needs at least 2 points");
  if (point_floats != shape.points() * 3)
    throw InputError("strand points: " + std::to_string(point_floats) + " floats given, " +
                     std::to_string(shape.points() * 3) + " expected for " + std::to_string(shape.strands) +
                     " strands of " + std::to_string(shape.points_per_strand) + " points");
  if (!(params.width > 0) || !std::isfinite(params.width))
    throw InputError("splatting width must be a positive finite number, got " + std::to_string(params.width));
  if (!(params.length_scale > 0) || !std::isfinite(params.length_scale))
    throw InputError("splatting length_scale must be a positive finite number, got " +
                     std::to_string(params.length_scale));
}

void segment_gaussian_forward(gpu::Stream& stream, const StrandShape& shape, const SegmentGaussianParams& params,
                              gpu::BufferRange points, gpu::BufferRange means, gpu::BufferRange covariances) {
  validate(shape, params, points.size / 4);
  gpu::require_bytes(means, shape.segments() * 12, "segment means");
  gpu::require_bytes(covariances, shape.segments() * 24, "segment covariances");
  gpu::Context& context = stream.context();
  const gpu::Kernel& kernel = context.kernel("splat/segment_gaussian_fwd", {{0, kWorkgroup}});
  const SegmentGaussianTerms<float> t(params);
  const std::uint64_t L = shape.points_per_strand;
  for_each_chunk(context, shape, [&](std::uint64_t first, std::uint64_t count) {
    const ForwardPush push{std::uint32_t(count), std::uint32_t(L), t.k2, t.eps2, t.delta2};
    stream.dispatch(kernel,
                    {gpu::sub_range(points, 4, first * L * 3, count * L * 3),
                     gpu::sub_range(means, 4, first * (L - 1) * 3, count * (L - 1) * 3),
                     gpu::sub_range(covariances, 4, first * (L - 1) * 6, count * (L - 1) * 6)},
                    push, gpu::Elements(count * (L - 1)));
  });
}

void segment_gaussian_backward(gpu::Stream& stream, const StrandShape& shape, const SegmentGaussianParams& params,
                               gpu::BufferRange points, gpu::BufferRange grad_means,
                               gpu::BufferRange grad_covariances, gpu::BufferRange grad_points, bool accumulate) {
  validate(shape, params, points.size / 4);
  gpu::require_bytes(grad_means, shape.segments() * 12, "segment mean gradients");
  gpu::require_bytes(grad_covariances, shape.segments() * 24, "segment covariance gradients");
  gpu::require_bytes(grad_points, shape.points() * 12, "strand point gradients");
  gpu::Context& context = stream.context();
  const gpu::Kernel& kernel = context.kernel("splat/segment_gaussian_bwd", {{0, kWorkgroup}});
  const SegmentGaussianTerms<float> t(params);
  const std::uint64_t L = shape.points_per_strand;
  for_each_chunk(context, shape, [&](std::uint64_t first, std::uint64_t count) {
    const BackwardPush push{std::uint32_t(count), std::uint32_t(L), t.k2, t.eps2, t.delta2, accumulate ? 1u : 0u};
    stream.dispatch(kernel,
                    {gpu::sub_range(points, 4, first * L * 3, count * L * 3),
                     gpu::sub_range(grad_means, 4, first * (L - 1) * 3, count * (L - 1) * 3),
                     gpu::sub_range(grad_covariances, 4, first * (L - 1) * 6, count * (L - 1) * 6),
                     gpu::sub_range(grad_points, 4, first * L * 3, count * L * 3)},
                    push, gpu::Elements(count * L));
  });
}

SegmentGaussians segment_gaussians(gpu::Context& context, const StrandShape& shape,
                                   const SegmentGaussianParams& params, std::span<const float> points) {
  validate(shape, params, points.size());
  require_finite(points, "strand points");
  gpu::Buffer<float> d_points(context, points, "strand points");
  gpu::Buffer<float> d_means(context, shape.segments() * 3, "segment means");
  gpu::Buffer<float> d_covs(context, shape.segments() * 6, "segment covariances");
  gpu::Stream stream(context);
  segment_gaussian_forward(stream, shape, params, d_points, d_means, d_covs);
  stream.submit_and_wait();
  return {d_means.download(), d_covs.download()};
}

std::vector<float> segment_gaussians_backward(gpu::Context& context, const StrandShape& shape,
                                              const SegmentGaussianParams& params, std::span<const float> points,
                                              std::span<const float> grad_means,
                                              std::span<const float> grad_covariances) {
  validate(shape, params, points.size());
  if (grad_means.size() != shape.segments() * 3 || grad_covariances.size() != shape.segments() * 6)
    throw InputError("segment gradients: sizes do not match " + std::to_string(shape.segments()) + " segments");
  require_finite(points, "strand points");
  require_finite(grad_means, "gradient of segment means");
  require_finite(grad_covariances, "gradient of segment covariances");
  gpu::Buffer<float> d_points(context, points, "strand points");
  gpu::Buffer<float> d_grad_means(context, grad_means, "grad segment means");
  gpu::Buffer<float> d_grad_covs(context, grad_covariances, "grad segment covariances");
  gpu::Buffer<float> d_grad_points(context, shape.points() * 3, "grad strand points");
  gpu::Stream stream(context);
  segment_gaussian_backward(stream, shape, params, d_points, d_grad_means, d_grad_covs, d_grad_points, false);
  stream.submit_and_wait();
  return d_grad_points.download();
}

}  // namespace nf::splat
