#include "engine/fur/strand_losses.hpp"

#include <cmath>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::fur {
namespace {

constexpr std::uint32_t kWorkgroup = 64;

struct BendingPush {
  std::uint32_t strands, points_per_strand;
  float guard_fraction;
};
struct MeanPush {
  std::uint32_t strands, bends, chunk, stage;
};
constexpr std::uint32_t kMeanChunk = 4096;  // strands one invocation sums (lavapipe cuts loops past 65,535)
struct LossPush {
  std::uint32_t strands, points_per_strand;
  float guard_fraction;
  std::int32_t nx, ny, nz;
  float ox, oy, oz, spacing;
};
struct LossBackwardPush {
  LossPush base;
  float w_direction, w_curvature, w_penetration;
  std::uint32_t accumulate;
};

LossPush loss_push(const StrandLossBatch& b) {
  return {b.shape.strands,      b.shape.points_per_strand, float(kSegmentGuardFraction), b.grid.dims[0], b.grid.dims[1],
          b.grid.dims[2],       float(b.grid.origin[0]),   float(b.grid.origin[1]),      float(b.grid.origin[2]),
          float(b.grid.spacing)};
}

}  // namespace

void validate(gpu::Context& context, const StrandLossShape& shape, const SdfGridRef& grid, std::uint64_t point_floats,
              std::uint64_t guide_floats, std::uint64_t length_floats, std::uint64_t sdf_floats) {
  if (shape.strands == 0) throw InputError("strand losses: the batch has no strands");
  if (shape.points_per_strand < 3) throw InputError("strand losses: a strand needs at least 3 points for its bending angles");
  const std::uint64_t n = shape.strands;
  if (point_floats != n * shape.points_per_strand * 3)
    throw InputError("strand losses: " + std::to_string(point_floats) + " point floats for " + std::to_string(n) + " strands of " +
                     std::to_string(shape.points_per_strand) + " points");
  if (guide_floats != n * 3) throw InputError("strand losses: one growth direction (3 floats) per strand expected");
  if (length_floats != n) throw InputError("strand losses: one fur length per strand expected");
  for (int a = 0; a < 3; ++a)
    if (grid.dims[std::size_t(a)] < 2) throw InputError("strand losses: the SDF grid needs at least 2 samples per axis");
  if (!(grid.spacing > 0) || !std::isfinite(grid.spacing)) throw InputError("strand losses: the SDF grid's spacing must be positive");
  if (sdf_floats != std::uint64_t(grid.dims[0]) * std::uint64_t(grid.dims[1]) * std::uint64_t(grid.dims[2]))
    throw InputError("strand losses: the SDF grid's values do not match its dimensions");
  const std::uint64_t limit = context.info().limits.max_storage_buffer_range;
  for (const auto& [bytes, what] : {std::pair{point_floats * 4, "strand points"}, std::pair{sdf_floats * 4, "SDF grid"}})
    if (bytes > limit)
      throw DeviceError(std::string("strand losses: the ") + what + " (" + std::to_string(bytes) +
                        " bytes) exceed one storage-buffer binding (" + std::to_string(limit) + "); use smaller batches");
}

StrandLossScratch::StrandLossScratch(gpu::Context& context, const StrandLossShape& shape)
    : theta(context, std::uint64_t(shape.strands) * (shape.points_per_strand - 2), "bending angles"),
      mean(context, shape.points_per_strand - 2, "mean bending angles"),
      mean_partial(context, std::uint64_t((shape.strands + kMeanChunk - 1) / kMeanChunk) * (shape.points_per_strand - 2),
                   "bending angle sums per chunk"),
      partial(context, std::uint64_t(shape.strands) * 3, "strand loss sums") {}

void strand_losses_forward(gpu::Stream& stream, const StrandLossBatch& b, StrandLossScratch& scratch) {
  gpu::Context& context = stream.context();
  validate(context, b.shape, b.grid, b.points.size / 4, b.guides.size / 4, b.lengths.size / 4, b.sdf.size / 4);
  const std::uint32_t bends = b.shape.points_per_strand - 2;
  stream.dispatch(context.kernel("fur/strand_bending", {{0, kWorkgroup}}), {b.points, b.lengths, scratch.theta},
                  BendingPush{b.shape.strands, b.shape.points_per_strand, float(kSegmentGuardFraction)}, gpu::Elements(b.shape.strands));
  const gpu::Kernel& mean = context.kernel("fur/strand_bending_mean", {{0, kWorkgroup}});
  const std::uint32_t chunks = (b.shape.strands + kMeanChunk - 1) / kMeanChunk;
  stream.dispatch(mean, {scratch.theta, scratch.mean_partial, scratch.mean}, MeanPush{b.shape.strands, bends, kMeanChunk, 0},
                  gpu::Elements(std::uint64_t(chunks) * bends));
  stream.dispatch(mean, {scratch.theta, scratch.mean_partial, scratch.mean}, MeanPush{b.shape.strands, bends, kMeanChunk, 1},
                  gpu::Elements(bends));
  stream.dispatch(context.kernel("fur/strand_losses_fwd", {{0, kWorkgroup}}),
                  {b.points, b.guides, b.lengths, scratch.theta, scratch.mean, b.sdf, scratch.partial}, loss_push(b),
                  gpu::Elements(b.shape.strands));
}

std::array<double, 3> strand_loss_values(const StrandLossScratch& scratch, const StrandLossShape& shape) {
  const std::vector<float> partial = scratch.partial.download();
  std::array<double, 3> sum{0, 0, 0};
  for (std::size_t i = 0; i < partial.size(); ++i) sum[i % 3] += double(partial[i]);
  const double N = shape.strands, L = shape.points_per_strand;
  return {sum[0] / (N * (L - 1)), sum[1] / (N * (L - 2)), sum[2] / (N * L)};
}

void strand_losses_backward(gpu::Stream& stream, const StrandLossBatch& b, const StrandLossScratch& scratch,
                            const StrandLossWeights& w, gpu::BufferRange grad_points, bool accumulate) {
  gpu::Context& context = stream.context();
  validate(context, b.shape, b.grid, b.points.size / 4, b.guides.size / 4, b.lengths.size / 4, b.sdf.size / 4);
  gpu::require_bytes(grad_points, b.points.size, "strand point gradients");
  const LossBackwardPush push{loss_push(b), float(w.direction), float(w.curvature), float(w.penetration), accumulate ? 1u : 0u};
  stream.dispatch(context.kernel("fur/strand_losses_bwd", {{0, kWorkgroup}}),
                  {b.points, b.guides, b.lengths, scratch.theta, scratch.mean, b.sdf, grad_points}, push,
                  gpu::Elements(b.shape.strands));
}

namespace {

struct Uploaded {
  gpu::Buffer<float> points, guides, lengths, sdf;
  StrandLossBatch batch;
};

Uploaded upload(gpu::Context& context, const StrandLossShape& shape, const SdfGridRef& grid, std::span<const float> points,
                std::span<const float> guides, std::span<const float> lengths, std::span<const float> sdf) {
  validate(context, shape, grid, points.size(), guides.size(), lengths.size(), sdf.size());
  require_finite(points, "strand points");
  require_finite(guides, "growth directions");
  require_finite(lengths, "fur lengths");
  require_finite(sdf, "SDF grid");
  Uploaded u{gpu::Buffer<float>(context, points, "strand points"), gpu::Buffer<float>(context, guides, "growth directions"),
             gpu::Buffer<float>(context, lengths, "fur lengths"), gpu::Buffer<float>(context, sdf, "SDF grid"), {}};
  u.batch = {shape, grid, u.points, u.guides, u.lengths, u.sdf};
  return u;
}

}  // namespace

std::array<double, 3> strand_losses(gpu::Context& context, const StrandLossShape& shape, const SdfGridRef& grid,
                                    std::span<const float> points, std::span<const float> guides,
                                    std::span<const float> lengths, std::span<const float> sdf) {
  Uploaded u = upload(context, shape, grid, points, guides, lengths, sdf);
  StrandLossScratch scratch(context, shape);
  gpu::Stream stream(context);
  strand_losses_forward(stream, u.batch, scratch);
  stream.submit_and_wait();
  return strand_loss_values(scratch, shape);
}

std::vector<float> strand_losses_gradient(gpu::Context& context, const StrandLossShape& shape, const SdfGridRef& grid,
                                          std::span<const float> points, std::span<const float> guides,
                                          std::span<const float> lengths, std::span<const float> sdf,
                                          const StrandLossWeights& weights) {
  Uploaded u = upload(context, shape, grid, points, guides, lengths, sdf);
  StrandLossScratch scratch(context, shape);
  gpu::Buffer<float> grad(context, points.size(), "strand point gradients");
  gpu::Stream stream(context);
  strand_losses_forward(stream, u.batch, scratch);
  strand_losses_backward(stream, u.batch, scratch, weights, grad, false);
  stream.submit_and_wait();
  return grad.download();
}

}  // namespace nf::fur
