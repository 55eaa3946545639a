#pragma once
// GPU NeuS volume rendering (compositing of per-sample SDF/colour outputs along rays), forward and
// hand-written adjoint. Maths, guards, kinks and layouts: volume_render_ref.hpp. Shaders:
// shaders/neus/volume_render_{fwd,bwd}.comp (one invocation per ray).
#include <cstdint>
#include <span>
#include <vector>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"
#include "engine/neus/volume_render_ref.hpp"

namespace nf::neus {

struct VolumeRenderShape {
  std::uint64_t rays = 0;
  std::uint32_t samples = 0;  // per ray, > 0
};
struct VolumeRenderParams {
  float inv_s = 64.f;          // > 0, finite (the caller clips exp(10 v) to [1e-6, 1e6])
  float cos_anneal = 1.f;      // in [0, 1], not differentiated
  std::uint64_t chunk_rays = 0;  // rays per dispatch, 0 = as many as a binding allows (tests lower it)
};

// Device arrays: sdf, cos, dist rays*samples floats; rgb rays*samples*3 floats.
struct VolumeRenderInputBuffers {
  gpu::BufferRange sdf, cos, dist, rgb;
};
struct VolumeRenderOutputBuffers {
  gpu::BufferRange colour, opacity;  // rays*3, rays
};
struct VolumeRenderGradientBuffers {
  gpu::BufferRange sdf, cos, rgb, inv_s;  // rays*samples, rays*samples, rays*samples*3, 1 float
};

// Throws InputError naming the bad parameter.
void validate(const VolumeRenderParams& params);

// Records the forward. Inputs are trusted to be finite (see the host conveniences).
void volume_render_forward(gpu::Stream& stream, VolumeRenderShape shape, const VolumeRenderParams& params,
                           const VolumeRenderInputBuffers& inputs, const VolumeRenderOutputBuffers& outputs);

// Records the adjoint of L = sum_r gcol_r . colour_r + gop_r opacity_r: overwrites all of `grads`
// (grads.inv_s is zeroed, then summed over every ray and sample by float atomics). Recomputes the
// forward per ray; needs no forward outputs.
void volume_render_backward(gpu::Stream& stream, VolumeRenderShape shape, const VolumeRenderParams& params,
                            const VolumeRenderInputBuffers& inputs, gpu::BufferRange grad_colour,
                            gpu::BufferRange grad_opacity, const VolumeRenderGradientBuffers& grads);

// Host conveniences (upload, run, download). Rays = sdf.size() / samples; inv_s is inputs.inv_s
// (params.inv_s is ignored). They check sizes and reject NaN/Inf with an InputError naming the input.
VolumeRenderOutputs<float> volume_render(gpu::Context& context, std::uint32_t samples,
                                         const VolumeRenderInputs<float>& inputs, const VolumeRenderParams& params);

struct VolumeRenderResult {
  VolumeRenderOutputs<float> outputs;
  VolumeRenderGradients<float> grads;
};
// Forward and adjoint in one submit.
VolumeRenderResult volume_render_with_gradients(gpu::Context& context, std::uint32_t samples,
                                                const VolumeRenderInputs<float>& inputs,
                                                const VolumeRenderParams& params, std::span<const float> grad_colour,
                                                std::span<const float> grad_opacity);

}  // namespace nf::neus
