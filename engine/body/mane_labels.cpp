#include "engine/body/mane_labels.hpp"

#include "engine/body/regions.hpp"
#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/point_index.hpp"

namespace nf::body {

ManeLabelling label_mane(geometry::Mesh& surface, const geometry::Mesh& fitted, const std::optional<HeadAxis>& head) {
  if (surface.regions.size() != surface.vertex_count()) throw InputError("mane: the surface has no regions");
  if (fitted.regions.size() != fitted.vertex_count() || fitted.vertex_count() == 0)
    throw InputError("mane: the fitted body has no regions");
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
  double total = 0, labelled = 0;
  for (std::size_t f = 0; f < surface.triangle_count(); ++f) {
    const std::uint32_t* t = &surface.triangles[3 * f];
    const glm::dvec3 a(surface.position(t[0])), b(surface.position(t[1])), c(surface.position(t[2]));
    const double third = glm::length(glm::cross(b - a, c - a)) / 6.0;
    total += 3 * third;
    for (int k = 0; k < 3; ++k) labelled += surface.regions[t[k]] == mane ? third : 0.0;
  }
  for (std::int32_t r : surface.regions) out.vertices += r == mane;
  out.area_share = total > 0 ? labelled / total : 0;
  return out;
}

json to_json(const ManeLabelling& m) {
  return {{"vertices", m.vertices}, {"area_share", m.area_share}, {"head_known", m.head_known}};
}

}  // namespace nf::body
