#include "engine/body/mane_labels.hpp"

#include "engine/body/regions.hpp"
#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/geometry/point_index.hpp"

namespace nf::body {

ManeLabelling label_mane(geometry::Mesh& surface, const geometry::Mesh& fitted, const std::optional<HeadAxis>& head,
                         const std::string& source) {
  if (surface.regions.size() != surface.vertex_count()) throw InputError("mane: the surface labelled from " + source + " has no regions");
  if (fitted.regions.size() != fitted.vertex_count() || fitted.vertex_count() == 0)
    throw InputError(source + ": the fitted body has no regions, so no mane can be placed on it");
  const std::int32_t neck = region_id(Region::neck), face = region_id(Region::face), mane = region_id(Region::mane);
  std::vector<std::uint8_t> zone(fitted.vertex_count(), 0);
  for (std::size_t v = 0; v < zone.size(); ++v) {
    const std::int32_t r = fitted.regions[v];
    zone[v] = r == neck || r == mane ||
              (r == face && head && glm::dot(glm::dvec3(fitted.position(v)) - head->centre, head->forward) < 0.0);
  }
  const geometry::PointIndex index(fitted.positions);
  parallel_for(surface.vertex_count(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const std::int32_t r = surface.regions[i];
      if ((r == neck || r == face) && zone[index.nearest(&surface.positions[3 * i]).first]) surface.regions[i] = mane;
    }
  });
  ManeLabelling out;
  out.head_known = head.has_value();
  const std::vector<double> area = geometry::vertex_areas(surface);
  double total = 0, labelled = 0;
  for (std::size_t v = 0; v < area.size(); ++v) {
    total += area[v];
    if (surface.regions[v] == mane) labelled += area[v], ++out.vertices;
  }
  out.area_share = total > 0 ? labelled / total : 0;
  return out;
}

json to_json(const ManeLabelling& m) {
  return {{"vertices", m.vertices}, {"area_share", m.area_share}, {"head_known", m.head_known}};
}

}  // namespace nf::body
