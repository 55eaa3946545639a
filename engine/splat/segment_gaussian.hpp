#pragma once
// GPU segment-to-Gaussian map of strand splatting (forward and hand-written adjoint). The maths, the
// zero-length guard and the storage layout are documented with the CPU reference in
// segment_gaussian_ref.hpp. Shaders: shaders/splat/segment_gaussian_{fwd,bwd}.comp.
#include <cstdint>
#include <span>
#include <vector>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/splat/segment_gaussian_ref.hpp"

namespace nf::splat {

struct StrandShape {
  std::uint32_t strands = 0;
  std::uint32_t points_per_strand = 0;  // L >= 2
  std::uint64_t points() const { return std::uint64_t(strands) * points_per_strand; }
  std::uint64_t segments() const { return std::uint64_t(strands) * (points_per_strand - 1); }
};

// Throws InputError naming the bad field (counts, sizes, width, length_scale).
void validate(const StrandShape& shape, const SegmentGaussianParams& params, std::uint64_t point_floats);

// Records the forward map on device buffers: points (points*3 floats) -> means (segments*3),
// covariances (segments*6). Inputs are trusted to be finite (see the host overload).
void segment_gaussian_forward(gpu::Stream& stream, const StrandShape& shape, const SegmentGaussianParams& params,
                              gpu::BufferRange points, gpu::BufferRange means, gpu::BufferRange covariances);

// Records the adjoint: grad_points (points*3) = dL/dpoints, added to its content when `accumulate`.
void segment_gaussian_backward(gpu::Stream& stream, const StrandShape& shape, const SegmentGaussianParams& params,
                               gpu::BufferRange points, gpu::BufferRange grad_means,
                               gpu::BufferRange grad_covariances, gpu::BufferRange grad_points, bool accumulate);

// Host conveniences (upload, run, download); these reject NaN/Inf with an error naming the input.
struct SegmentGaussians {
  std::vector<float> means, covariances;
};
SegmentGaussians segment_gaussians(gpu::Context& context, const StrandShape& shape,
                                   const SegmentGaussianParams& params, std::span<const float> points);
std::vector<float> segment_gaussians_backward(gpu::Context& context, const StrandShape& shape,
                                              const SegmentGaussianParams& params, std::span<const float> points,
                                              std::span<const float> grad_means,
                                              std::span<const float> grad_covariances);

}  // namespace nf::splat
