#pragma once
// Differentiable strand rasterisation on the GPU: strands -> one Gaussian per segment -> EWA
// projection -> 8x8 tiles with (tile, depth) keys sorted by the radix sort -> front-to-back
// compositing of 5 channels (hair alpha, orientation as a doubled-angle vector, confidence,
// depth), with the body's depth map hiding what lies behind it. The backward pass is the exact
// adjoint, down to the strand points and the per-segment confidence. Maths, guards and layouts:
// rasterizer_ref.hpp (the CPU reference). Shaders: shaders/splat/rasterize_*.comp.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/io/scene.hpp"
#include "engine/splat/rasterizer_ref.hpp"
#include "engine/splat/segment_gaussian.hpp"

namespace nf::splat {

// Throws InputError naming the field (image size, intrinsics, near/far, pose).
void validate(const RasterCamera& camera);

// The rasteriser's camera for a scene camera (same pixel and axis conventions).
RasterCamera raster_camera(const io::Camera& camera, double near, double far);

// The most segments one view may hold on this device: compositing reads any Gaussian of the view by
// index, so the projected Gaussians (and their gradients) must fit one storage binding (2.8 M
// segments at lavapipe's 128 MiB).
std::uint64_t max_segments_per_view(const gpu::Context& context);

class StrandRasterizer {
 public:
  explicit StrandRasterizer(gpu::Context& context);
  ~StrandRasterizer();
  StrandRasterizer(const StrandRasterizer&) = delete;
  StrandRasterizer& operator=(const StrandRasterizer&) = delete;

  // Renders `image` (5 planes of H x W floats). points: strands x L x 3; confidence: one per
  // segment; body_depth: H x W floats (depth along the view axis, +inf where no body), or empty.
  // Submits work and waits once in the middle (the number of tile entries sizes the sort).
  void forward(const StrandShape& shape, gpu::BufferRange points, gpu::BufferRange confidence, const RasterCamera& camera,
               const RasterParams& params, gpu::BufferRange body_depth, gpu::BufferRange image);
  // The adjoint of the last forward (same inputs): grad_image (5 planes) -> grad_points (N x L x 3,
  // added when `accumulate`) and grad_confidence (per segment, overwritten). Records into `stream`.
  void backward(gpu::Stream& stream, gpu::BufferRange grad_image, gpu::BufferRange grad_points,
                gpu::BufferRange grad_confidence, bool accumulate);

  // Tile entries (Gaussian x tile pairs) of the last forward.
  std::uint64_t tile_entries() const;
  // Compositing passes of the last forward (more than one where a tile's list is longer than a
  // pass may walk on this device: RasterParams::walk_chunk).
  std::uint32_t walk_passes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Host conveniences (upload, run, download); NaN/Inf inputs are refused naming the array.
std::vector<float> rasterize(gpu::Context& context, const StrandShape& shape, std::span<const float> points,
                             std::span<const float> confidence, const RasterCamera& camera, const RasterParams& params,
                             std::span<const float> body_depth = {});
struct RasterGradients {
  std::vector<float> points, confidence;
};
RasterGradients rasterize_backward(gpu::Context& context, const StrandShape& shape, std::span<const float> points,
                                   std::span<const float> confidence, const RasterCamera& camera,
                                   const RasterParams& params, std::span<const float> body_depth,
                                   std::span<const float> grad_image);

}  // namespace nf::splat
