#pragma once
// GPU image-space losses of strand splatting (silhouette L1 and Gabor orientation with rendered
// confidence), forward and hand-written adjoint. Formulas, normalisers, guards, kink conventions and
// layouts: image_losses_ref.hpp. Shaders: shaders/splat/image_losses_{fwd,bwd}.comp.
#include <cstdint>
#include <span>
#include <vector>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/splat/image_losses_ref.hpp"

namespace nf::splat {

struct ImageSize {
  std::uint32_t width = 0, height = 0;
  std::uint64_t pixels() const { return std::uint64_t(width) * height; }
};

// Device arrays of one view: pixels floats each; orientation holds two planes (x, then y), pixels * 2
// floats. Ranges may start at any float offset (e.g. planes 0, 1-2 and 3 of the rasteriser's image
// and of its gradient image): the wrapper binds them from an aligned offset and shifts indices.
struct ImageLossInputBuffers {
  gpu::BufferRange alpha, orientation, tau;
};
struct ImageLossTargetBuffers {
  gpu::BufferRange mask, weight, gabor_angle, gabor_confidence;
};
struct ImageLossGradientBuffers {
  gpu::BufferRange alpha, orientation, tau;
};

// Throws InputError naming the bad parameter (non-positive or non-finite floors and thresholds).
void validate(const ImageLossParams& params);

// Records the forward: writes 4 floats to `losses` = (L_sil, L_dir, N_sil, N_dir), the layout of
// ImageLossValues. Inputs are trusted to be finite (see the host conveniences). Empty images give
// (0, 0, norm_floor, norm_floor).
void image_losses_forward(gpu::Stream& stream, ImageSize size, const ImageLossParams& params,
                          const ImageLossInputBuffers& inputs, const ImageLossTargetBuffers& targets,
                          gpu::BufferRange losses);

// Records the adjoint of L = grad_silhouette * L_sil + grad_orientation * L_dir (e.g. 0.1 and 1000):
// overwrites `grads` (alpha, tau: pixels floats; orientation: pixels * 2). Reads N_sil, N_dir from
// `losses`, written by image_losses_forward on the same inputs earlier in this stream (or before);
// it is bound as a uniform, so its offset must be a multiple of minUniformBufferOffsetAlignment
// (a buffer of its own always is). Zero weight gives zero gradients; so does |o| <= orientation_min
// for dL/do and dL/dtau, and tau <= tau_floor for dL/dtau.
void image_losses_backward(gpu::Stream& stream, ImageSize size, const ImageLossParams& params,
                           const ImageLossInputBuffers& inputs, const ImageLossTargetBuffers& targets,
                           gpu::BufferRange losses, float grad_silhouette, float grad_orientation,
                           const ImageLossGradientBuffers& grads);

// Host conveniences (upload, run, download). They check sizes, reject NaN/Inf and negative weight or
// confidence with an InputError naming the input.
ImageLossValues<float> image_losses(gpu::Context& context, ImageSize size, const ImageLossInputs<float>& inputs,
                                    const ImageLossTargets<float>& targets, const ImageLossParams& params = {});

struct ImageLossResult {
  ImageLossValues<float> values;
  ImageLossGradients<float> grads;
};
// Forward and adjoint in one submit.
ImageLossResult image_losses_with_gradients(gpu::Context& context, ImageSize size,
                                            const ImageLossInputs<float>& inputs,
                                            const ImageLossTargets<float>& targets, float grad_silhouette,
                                            float grad_orientation, const ImageLossParams& params = {});

}  // namespace nf::splat
