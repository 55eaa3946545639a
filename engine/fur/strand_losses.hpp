#pragma once
// The fur stage's geometric strand losses on the GPU: growth direction against the knowledge,
// curvature consistency across the batch, penetration into the bald body; their forward values and
// hand-written adjoint. The maths and guards: strand_losses_ref.hpp. Shaders:
// shaders/fur/strand_bending{,_mean}.comp, strand_losses_{fwd,bwd}.comp.
#include <array>
#include <span>
#include <vector>

#include "engine/fur/strand_losses_ref.hpp"
#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::fur {

struct StrandLossWeights {  // the paper's
  double direction = 1.0, curvature = 0.01, penetration = 1.0;
};

// InputError naming the field (counts, sizes, grid) when the batch or grid is unusable; DeviceError
// when an array exceeds one storage-buffer binding (the fur stage's batches are far below).
void validate(gpu::Context& context, const StrandLossShape& shape, const SdfGridRef& grid, std::uint64_t point_floats,
              std::uint64_t guide_floats, std::uint64_t length_floats, std::uint64_t sdf_floats);

// Device inputs of one batch.
struct StrandLossBatch {
  StrandLossShape shape;
  SdfGridRef grid;
  gpu::BufferRange points, guides, lengths, sdf;  // N L 3, N 3 (unit), N, the grid's values
};

// Scratch of one batch size: the bending angles, their mean (and its per-chunk sums), the
// per-strand loss sums.
struct StrandLossScratch {
  StrandLossScratch(gpu::Context& context, const StrandLossShape& shape);
  gpu::Buffer<float> theta, mean, mean_partial, partial;
};

// Records the bending angles, their batch mean and the per-strand sums.
void strand_losses_forward(gpu::Stream& stream, const StrandLossBatch& batch, StrandLossScratch& scratch);
// After the forward has run: the three losses {direction, curvature, penetration} (unweighted).
std::array<double, 3> strand_loss_values(const StrandLossScratch& scratch, const StrandLossShape& shape);
// Records dLoss/dpoints for Loss = weights . losses; needs the forward recorded before it.
void strand_losses_backward(gpu::Stream& stream, const StrandLossBatch& batch, const StrandLossScratch& scratch,
                            const StrandLossWeights& weights, gpu::BufferRange grad_points, bool accumulate);

// Host conveniences (upload, run, download); NaN/Inf refused naming the input.
std::array<double, 3> strand_losses(gpu::Context& context, const StrandLossShape& shape, const SdfGridRef& grid,
                                    std::span<const float> points, std::span<const float> guides,
                                    std::span<const float> lengths, std::span<const float> sdf);
std::vector<float> strand_losses_gradient(gpu::Context& context, const StrandLossShape& shape, const SdfGridRef& grid,
                                          std::span<const float> points, std::span<const float> guides,
                                          std::span<const float> lengths, std::span<const float> sdf,
                                          const StrandLossWeights& weights);

}  // namespace nf::fur
