#include "engine/body/region_transfer.hpp"

#include <cmath>

#include <glm/glm.hpp>

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/geometry/surface_locator.hpp"

namespace nf::body {

std::vector<std::int32_t> nearest_regions(const geometry::Mesh& target, const geometry::Mesh& labelled) {
  if (labelled.regions.size() != labelled.vertex_count() || labelled.vertex_count() == 0)
    throw InputError("region transfer: the labelled mesh has no regions");
  const geometry::PointIndex index(labelled.positions);
  std::vector<std::int32_t> out(target.vertex_count());
  parallel_for(out.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) out[i] = labelled.regions[index.nearest(&target.positions[3 * i]).first];
  });
  return out;
}

RegionDetail attach_region_detail(const BodyModel& model, const geometry::Mesh& fine) {
  if (fine.regions.size() != fine.vertex_count()) throw InternalError("region detail: the finer surface has no regions");
  const geometry::Mesh rest = rest_mesh(model);
  const geometry::SurfaceLocator locator(rest);
  RegionDetail d;
  d.faces.resize(fine.vertex_count());
  d.barycentric.resize(3 * fine.vertex_count());
  d.regions = fine.regions;
  parallel_for(fine.vertex_count(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const geometry::SurfaceHit hit = locator.closest(fine.position(i));
      d.faces[i] = hit.face;
      for (int k = 0; k < 3; ++k) d.barycentric[3 * i + k] = hit.barycentric[k];
    }
  });
  return d;
}

geometry::Mesh region_carrier(const BodyModel& model, const geometry::Mesh& posed) {
  const RegionDetail& d = model.region_detail;
  if (d.size() == 0) return posed;
  if (posed.vertex_count() != model.vertex_count())
    throw InternalError("region detail: the posed body has " + std::to_string(posed.vertex_count()) + " vertices, the model " +
                        std::to_string(model.vertex_count()));
  geometry::Mesh points;
  points.positions.resize(3 * d.size());
  points.regions = d.regions;
  for (std::size_t i = 0; i < d.size(); ++i) {
    glm::vec3 p(0.0f);
    for (int k = 0; k < 3; ++k) p += d.barycentric[3 * i + k] * posed.position(model.triangles[3 * d.faces[i] + k]);
    for (int k = 0; k < 3; ++k) points.positions[3 * i + k] = p[k];
  }
  return points;
}

std::size_t pads_face_down(geometry::Mesh& mesh, const glm::dvec3& up) {
  if (mesh.regions.size() != mesh.vertex_count() || mesh.normals.size() != mesh.positions.size())
    throw InputError("pads by their normals: the mesh needs regions and normals");
  const std::int32_t pads = region_id(Region::paw_pads);
  // A paw's fur, or its leg where the fit's paw took none (a short leg in long fur).
  const auto on_the_leg = [](std::int32_t r) {
    return r == region_id(Region::front_paws) || r == region_id(Region::paws) || r == region_id(Region::leg_front) ||
           r == region_id(Region::leg_rear);
  };
  const glm::dvec3 u = glm::normalize(up);
  std::vector<float> fur_xyz;
  std::vector<std::int32_t> fur_region;
  std::vector<std::size_t> sideways;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const std::int32_t r = mesh.regions[v];
    if (on_the_leg(r)) {
      fur_xyz.insert(fur_xyz.end(), &mesh.positions[3 * v], &mesh.positions[3 * v] + 3);
      fur_region.push_back(r);
    } else if (r == pads) {
      const glm::dvec3 n(mesh.normals[3 * v], mesh.normals[3 * v + 1], mesh.normals[3 * v + 2]);
      if (glm::dot(n, u) >= -kPadFacing * glm::length(n)) sideways.push_back(v);  // a zero normal faces nowhere: not a pad
    }
  }
  if (fur_region.empty() || sideways.empty()) return 0;
  const geometry::PointIndex index(fur_xyz);
  for (const std::size_t v : sideways) mesh.regions[v] = fur_region[index.nearest(&mesh.positions[3 * v]).first];
  return sideways.size();
}

RegionAccuracy region_accuracy(const geometry::Mesh& mesh, const geometry::Mesh& reference) {
  if (mesh.regions.size() != mesh.vertex_count()) throw InputError("region accuracy: the mesh has no regions");
  const std::vector<std::int32_t> truth = nearest_regions(mesh, reference);
  const std::vector<double> vertex_area = geometry::vertex_areas(mesh);
  RegionAccuracy r;
  std::array<double, kRegionCount> correct{};
  double total = 0, right = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const std::int32_t t = truth[i];
    if (t < 0 || t >= kRegionCount) continue;
    total += vertex_area[i];
    r.area[std::size_t(t)] += vertex_area[i];
    if (mesh.regions[i] == t) right += vertex_area[i], correct[std::size_t(t)] += vertex_area[i];
  }
  r.accuracy = total > 0 ? right / total : 0;
  for (int k = 0; k < kRegionCount; ++k) {
    r.recall[std::size_t(k)] = r.area[std::size_t(k)] > 0 ? correct[std::size_t(k)] / r.area[std::size_t(k)] : -1;
    r.area[std::size_t(k)] = total > 0 ? r.area[std::size_t(k)] / total : 0;
  }
  return r;
}

json to_json(const RegionAccuracy& a) {
  json recall = json::object(), area = json::object();
  for (int k = 0; k < kRegionCount; ++k) {
    if (a.recall[std::size_t(k)] < 0) continue;
    recall[std::string(kRegionNames[std::size_t(k)])] = a.recall[std::size_t(k)];
    area[std::string(kRegionNames[std::size_t(k)])] = a.area[std::size_t(k)];
  }
  return {{"accuracy", a.accuracy}, {"recall", recall}, {"area_share", area}};
}

}  // namespace nf::body
