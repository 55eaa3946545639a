#include "engine/synth/effective_thickness.hpp"

#include <vector>

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/core/stats.hpp"
#include "engine/geometry/surface_locator.hpp"

namespace nf::synth {

std::array<float, body::kRegionCount> effective_thickness(const geometry::Mesh& bald, const geometry::Mesh& envelope) {
  if (bald.regions.size() != bald.vertex_count()) throw InternalError("effective_thickness: the bald body has no region per vertex");
  // The envelope lies up to a few centimetres off the body (a lion's mane): more candidate vertices
  // than the locator's default keep its closest face among them.
  const geometry::SurfaceLocator locator(envelope, 16);
  std::vector<double> gap(bald.vertex_count());
  parallel_for(bald.vertex_count(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v)
      gap[v] = locator.closest({bald.positions[3 * v], bald.positions[3 * v + 1], bald.positions[3 * v + 2]}).distance;
  });
  std::array<std::vector<double>, body::kRegionCount> per_region;
  for (std::size_t v = 0; v < gap.size(); ++v) {
    const std::int32_t r = bald.regions[v];
    if (r >= 0 && r < body::kRegionCount) per_region[std::size_t(r)].push_back(gap[v]);
  }
  std::array<float, body::kRegionCount> thickness;
  for (std::size_t r = 0; r < per_region.size(); ++r)
    thickness[r] = per_region[r].empty() ? -1.0f : float(median(std::move(per_region[r])));
  return thickness;
}

}  // namespace nf::synth
