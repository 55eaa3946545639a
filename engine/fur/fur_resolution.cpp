#include "engine/fur/fur_resolution.hpp"

#include <algorithm>
#include <utility>
#include <vector>

#include "engine/core/stats.hpp"

namespace nf::fur {

double fur_length_pixels(const FurView& view, const Roots& roots, std::size_t samples) {
  const std::size_t n = std::max<std::size_t>(1, samples);
  const std::size_t stride = std::max<std::size_t>(1, (roots.size() + n - 1) / n);
  std::vector<double> lengths;
  for (std::size_t i = 0; i < roots.size(); i += stride) {
    const glm::dvec3 p = view.crop.project(glm::dvec3(roots.position[i]));
    if (!(p.z > 0) || p.x < 0 || p.y < 0 || p.x >= view.crop.width || p.y >= view.crop.height) continue;
    // crop.fx is the photo's focal scaled to the rendering grid: divide the scale back out.
    lengths.push_back(double(roots.length[i]) * view.crop.fx / p.z / view.scale);
  }
  return median(std::move(lengths));  // 0 when no root is in view
}

double image_loss_weight(double fur_pixels, double resolved_px) {
  if (!(resolved_px > 0)) return 1;
  return std::clamp(2 * fur_pixels / resolved_px - 1, 0.0, 1.0);
}

std::uint32_t gabor_scales_for(double fur_pixels, double resolved_px, std::uint32_t most) {
  std::uint32_t scales = 1;
  const double needed = 2 * std::max(resolved_px, 1.0);
  while (scales < most && fur_pixels / double(1u << scales) >= needed) ++scales;
  return std::max(1u, std::min(scales, most));
}

}  // namespace nf::fur
