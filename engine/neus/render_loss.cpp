#include "engine/neus/render_loss.hpp"

#include <algorithm>
#include <cmath>

#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::neus {
namespace {
constexpr std::uint32_t kWorkgroup = 64;
struct LossPush {
  std::uint32_t rays;
  float colour_weight, mask_weight;
};
}  // namespace

std::uint32_t render_loss_partial_count(std::uint32_t rays) { return std::max(1u, (rays + kWorkgroup - 1) / kWorkgroup); }

void render_loss(gpu::Stream& stream, std::uint32_t rays, std::uint32_t inside_rays, const RenderLossWeights& w,
                 gpu::BufferRange colour, gpu::BufferRange opacity, gpu::BufferRange target,
                 gpu::BufferRange grad_colour, gpu::BufferRange grad_opacity, gpu::BufferRange partials) {
  if (rays == 0) return;
  gpu::require_bytes(colour, std::uint64_t(rays) * 12, "render loss colour");
  gpu::require_bytes(opacity, std::uint64_t(rays) * 4, "render loss opacity");
  gpu::require_bytes(target, std::uint64_t(rays) * 16, "render loss target");
  gpu::require_bytes(grad_colour, std::uint64_t(rays) * 12, "render loss colour gradient");
  gpu::require_bytes(grad_opacity, std::uint64_t(rays) * 4, "render loss opacity gradient");
  gpu::require_bytes(partials, std::uint64_t(render_loss_partial_count(rays)) * 16, "render loss partials");
  const LossPush push{rays, w.colour / float(std::max(1u, inside_rays)), w.mask / float(rays)};
  stream.dispatch(stream.context().kernel("neus/render_loss", {{0, kWorkgroup}}),
                  {colour, opacity, target, grad_colour, grad_opacity, partials}, push,
                  gpu::Elements(std::uint64_t(render_loss_partial_count(rays)) * kWorkgroup));
}

double RenderLossTotals::loss(const RenderLossWeights& w) const {
  return w.colour * colour_l1 / std::max(1.0, inside) + w.mask * bce;
}

double RenderLossTotals::psnr() const {
  if (!(inside > 0)) return 0.0;
  const double mse = squared_error / (3.0 * inside);
  return mse > 0 ? -10.0 * std::log10(mse) : 99.0;
}

RenderLossTotals sum_render_loss(const std::vector<glm::vec4>& partials, std::uint32_t rays) {
  RenderLossTotals t;
  for (const glm::vec4& p : partials) {
    t.colour_l1 += p.x, t.bce += p.y, t.squared_error += p.z, t.inside += p.w;
  }
  t.bce /= std::max(1u, rays);
  return t;
}

}  // namespace nf::neus
