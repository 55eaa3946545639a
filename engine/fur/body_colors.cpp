#include "engine/fur/body_colors.hpp"

#include <algorithm>

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/surface_locator.hpp"

namespace nf::fur {
namespace {

double mean_edge(const geometry::Mesh& m) {
  double sum = 0;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
    for (int e = 0; e < 3; ++e) sum += glm::distance(m.position(m.triangles[t + e]), m.position(m.triangles[t + (e + 1) % 3]));
  return m.triangles.empty() ? 0.0 : sum / double(m.triangles.size());
}

}  // namespace

StrandControls body_color_points(const geometry::Mesh& bald, const geometry::Mesh& envelope) {
  NF_CHECK(envelope.triangle_count() > 0, "body colours: M_NeuS has no triangle");
  const geometry::SurfaceLocator locate(envelope);
  const float floor = float(2.0 * mean_edge(envelope));
  const std::size_t n = bald.vertex_count();
  StrandControls c;
  c.strands = std::uint32_t(n), c.controls = 1;
  c.points.resize(3 * n), c.lengths.resize(n);
  c.roots.assign(bald.positions.begin(), bald.positions.end());
  parallel_for(n, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      const geometry::SurfaceHit hit = locate.closest(bald.position(v));
      c.points[3 * v] = hit.point.x, c.points[3 * v + 1] = hit.point.y, c.points[3 * v + 2] = hit.point.z;
      c.lengths[v] = floor;  // the point lies on M_NeuS: the fur's depth does not widen its tolerance
    }
  });
  return c;
}

StrandColorOptions body_color_options(StrandColorOptions options) {
  options.controls = 1;
  options.hidden_depth = 0.5;  // of two mean edges: M_NeuS's own rasterised depth, not the fur's (fur.color_hidden_depth)
  return options;
}

}  // namespace nf::fur
