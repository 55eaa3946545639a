#include "engine/fur/strand_geometry.hpp"

#include <algorithm>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::fur {
namespace {

struct Push {
  std::uint32_t strands, segments, row_stride;
  float delta2;
};

constexpr std::uint32_t kWorkgroup = 64;

// Strand chunks whose every binding fits the device's storage-buffer range.
template <class Body>
void for_each_chunk(gpu::Context& context, const StrandGeometryShape& shape, const Body& body) {
  const std::uint64_t chunk =
      gpu::items_per_chunk(context, {std::uint64_t(shape.row_stride) * 4, kFrameFloats * 4, std::uint64_t(shape.points()) * 12});
  for (std::uint64_t first = 0; first < shape.strands; first += chunk)
    body(first, std::min<std::uint64_t>(chunk, shape.strands - first));
}

}  // namespace

void validate(const StrandGeometryShape& shape, std::uint64_t row_floats, std::uint64_t frame_floats) {
  if (shape.segments < 1) throw InputError("strand geometry: a strand needs at least one segment");
  if (shape.row_stride < 3ull * shape.segments)
    throw InputError("strand geometry: row stride " + std::to_string(shape.row_stride) + " is below 3 x " +
                     std::to_string(shape.segments) + " segments");
  if (row_floats != std::uint64_t(shape.strands) * shape.row_stride)
    throw InputError("strand geometry: " + std::to_string(row_floats) + " row floats for " + std::to_string(shape.strands) +
                     " strands of stride " + std::to_string(shape.row_stride));
  if (frame_floats != std::uint64_t(shape.strands) * kFrameFloats)
    throw InputError("strand geometry: " + std::to_string(frame_floats) + " frame floats for " + std::to_string(shape.strands) +
                     " strands (13 each: root, length, tangent, bitangent, normal)");
}

void strand_geometry_forward(gpu::Stream& stream, const StrandGeometryShape& shape, gpu::BufferRange rows,
                             gpu::BufferRange frames, gpu::BufferRange points) {
  validate(shape, rows.size / 4, frames.size / 4);
  gpu::require_bytes(points, std::uint64_t(shape.strands) * shape.points() * 12, "strand points");
  gpu::Context& context = stream.context();
  const gpu::Kernel& kernel = context.kernel("fur/strand_geometry_fwd", {{0, kWorkgroup}});
  const std::uint64_t R = shape.row_stride, P3 = std::uint64_t(shape.points()) * 3;
  for_each_chunk(context, shape, [&](std::uint64_t first, std::uint64_t count) {
    const Push push{std::uint32_t(count), shape.segments, shape.row_stride, float(kArcGuard * kArcGuard)};
    stream.dispatch(kernel,
                    {gpu::sub_range(rows, 4, first * R, count * R), gpu::sub_range(frames, 4, first * kFrameFloats, count * kFrameFloats),
                     gpu::sub_range(points, 4, first * P3, count * P3)},
                    push, gpu::Elements(count));
  });
}

void strand_geometry_backward(gpu::Stream& stream, const StrandGeometryShape& shape, gpu::BufferRange rows,
                              gpu::BufferRange frames, gpu::BufferRange grad_points, gpu::BufferRange grad_rows,
                              gpu::BufferRange grad_frames) {
  validate(shape, rows.size / 4, frames.size / 4);
  gpu::require_bytes(grad_points, std::uint64_t(shape.strands) * shape.points() * 12, "strand point gradients");
  gpu::require_bytes(grad_rows, std::uint64_t(shape.strands) * shape.row_stride * 4, "decoder row gradients");
  gpu::require_bytes(grad_frames, std::uint64_t(shape.strands) * kFrameFloats * 4, "frame gradients");
  gpu::Context& context = stream.context();
  const gpu::Kernel& kernel = context.kernel("fur/strand_geometry_bwd", {{0, kWorkgroup}});
  const std::uint64_t R = shape.row_stride, P3 = std::uint64_t(shape.points()) * 3;
  for_each_chunk(context, shape, [&](std::uint64_t first, std::uint64_t count) {
    const Push push{std::uint32_t(count), shape.segments, shape.row_stride, float(kArcGuard * kArcGuard)};
    stream.dispatch(kernel,
                    {gpu::sub_range(rows, 4, first * R, count * R), gpu::sub_range(frames, 4, first * kFrameFloats, count * kFrameFloats),
                     gpu::sub_range(grad_points, 4, first * P3, count * P3), gpu::sub_range(grad_rows, 4, first * R, count * R),
                     gpu::sub_range(grad_frames, 4, first * kFrameFloats, count * kFrameFloats)},
                    push, gpu::Elements(count));
  });
}

std::vector<float> strand_points(gpu::Context& context, const StrandGeometryShape& shape, std::span<const float> rows,
                                 std::span<const float> frames) {
  validate(shape, rows.size(), frames.size());
  require_finite(rows, "decoder rows");
  require_finite(frames, "strand frames");
  gpu::Buffer<float> d_rows(context, rows, "decoder rows"), d_frames(context, frames, "strand frames");
  gpu::Buffer<float> d_points(context, std::uint64_t(shape.strands) * shape.points() * 3, "strand points");
  gpu::Stream stream(context);
  strand_geometry_forward(stream, shape, d_rows, d_frames, d_points);
  stream.submit_and_wait();
  return d_points.download();
}

StrandGeometryGradients strand_points_backward(gpu::Context& context, const StrandGeometryShape& shape,
                                               std::span<const float> rows, std::span<const float> frames,
                                               std::span<const float> grad_points) {
  validate(shape, rows.size(), frames.size());
  if (grad_points.size() != std::uint64_t(shape.strands) * shape.points() * 3)
    throw InputError("strand geometry: the point gradients do not match " + std::to_string(shape.strands) + " strands");
  require_finite(rows, "decoder rows");
  require_finite(frames, "strand frames");
  require_finite(grad_points, "strand point gradients");
  gpu::Buffer<float> d_rows(context, rows, "decoder rows"), d_frames(context, frames, "strand frames");
  gpu::Buffer<float> d_grad_points(context, grad_points, "strand point gradients");
  gpu::Buffer<float> d_grad_rows(context, rows.size(), "decoder row gradients");
  gpu::Buffer<float> d_grad_frames(context, frames.size(), "frame gradients");
  gpu::Stream stream(context);
  strand_geometry_backward(stream, shape, d_rows, d_frames, d_grad_points, d_grad_rows, d_grad_frames);
  stream.submit_and_wait();
  return {d_grad_rows.download(), d_grad_frames.download()};
}

}  // namespace nf::fur
