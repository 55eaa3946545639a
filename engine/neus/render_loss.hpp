#pragma once
// NeuS image losses per ray on the GPU (shaders/neus/render_loss.comp): colour L1 on rays inside
// the mask and mask binary cross-entropy on every ray, with their gradients.
#include <cstdint>

#include <glm/glm.hpp>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::neus {

struct RenderLossWeights {
  float colour = 1.f;  // NeuS: L1 summed over channels, over the rays inside the mask
  float mask = 0.1f;   // NeuS: BCE, mean over rays
};

// colour [R][3], opacity [R], target [R] (rgb, mask in {0, 1}); writes grad_colour [R][3],
// grad_opacity [R] and per-workgroup partial sums into `partials` (partial_count(R) vec4: colour L1,
// BCE, squared colour error inside the mask, rays inside the mask). inside_rays scales the colour term.
void render_loss(gpu::Stream& stream, std::uint32_t rays, std::uint32_t inside_rays, const RenderLossWeights& weights,
                 gpu::BufferRange colour, gpu::BufferRange opacity, gpu::BufferRange target,
                 gpu::BufferRange grad_colour, gpu::BufferRange grad_opacity, gpu::BufferRange partials);
std::uint32_t render_loss_partial_count(std::uint32_t rays);

struct RenderLossTotals {
  double colour_l1 = 0, bce = 0, squared_error = 0, inside = 0;
  double loss(const RenderLossWeights& w) const;  // the weighted loss the gradients belong to
  double psnr() const;                            // inside the mask, colours in [0, 1]
};
RenderLossTotals sum_render_loss(const std::vector<glm::vec4>& partials, std::uint32_t rays);

}  // namespace nf::neus
