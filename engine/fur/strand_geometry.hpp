#pragma once
// The strand geometry map of the fur stage on the GPU: the strand prior's segment vectors to world
// points (running sum, arc length normalised to the root's fur length, the root's frame), and its
// hand-written adjoint. The maths, guard and layouts: strand_geometry_ref.hpp. Shaders:
// shaders/fur/strand_geometry_{fwd,bwd}.comp.
#include <span>
#include <vector>

#include "engine/fur/strand_geometry_ref.hpp"
#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::fur {

// InputError naming the field (segments, row stride, array sizes).
void validate(const StrandGeometryShape& shape, std::uint64_t row_floats, std::uint64_t frame_floats);

// Records points = map(rows, frames). Inputs are trusted to be finite (the host overload checks).
void strand_geometry_forward(gpu::Stream& stream, const StrandGeometryShape& shape, gpu::BufferRange rows,
                             gpu::BufferRange frames, gpu::BufferRange points);
// Records the adjoint: grad_rows (the rows' layout, padding 0) and grad_frames (13 per strand),
// both overwritten.
void strand_geometry_backward(gpu::Stream& stream, const StrandGeometryShape& shape, gpu::BufferRange rows,
                              gpu::BufferRange frames, gpu::BufferRange grad_points, gpu::BufferRange grad_rows,
                              gpu::BufferRange grad_frames);

// Host conveniences (upload, run, download); NaN/Inf refused naming the input.
std::vector<float> strand_points(gpu::Context& context, const StrandGeometryShape& shape, std::span<const float> rows,
                                 std::span<const float> frames);
struct StrandGeometryGradients {
  std::vector<float> rows, frames;
};
StrandGeometryGradients strand_points_backward(gpu::Context& context, const StrandGeometryShape& shape,
                                               std::span<const float> rows, std::span<const float> frames,
                                               std::span<const float> grad_points);

}  // namespace nf::fur
