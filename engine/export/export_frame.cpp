#include "engine/export/export_frame.hpp"

#include <cmath>
#include <limits>

#include "engine/core/error.hpp"
#include "engine/geometry/mesh_tools.hpp"

namespace nf::exporter {

glm::vec3 ExportFrame::direction(const glm::vec3& world) const {
  const glm::dvec3 d = glm::dmat3(world_to_export) * glm::dvec3(world);
  const double n = glm::length(d);
  return n > 0 ? glm::vec3(d / n) : glm::vec3(0.f);
}

json ExportFrame::to_json() const {
  return {{"world_to_export", json_matrix_rows(world_to_export)}, {"metres_per_scene_unit", metres_per_unit}, {"axes", "+x animal's left, +y up, +z forward (glTF)"},
          {"unit", "metre"}};
}

ExportFrame export_frame(const glm::dmat4& animal_to_world, double cm_per_unit, const geometry::Mesh& body_world) {
  if (!(cm_per_unit > 0) || !std::isfinite(cm_per_unit))
    throw InputError("export: the metric scale is " + std::to_string(cm_per_unit) + " cm per scene unit; it must be positive (knowledge/scale.json)");
  const glm::dmat3 a(animal_to_world);
  const double s = std::cbrt(std::abs(glm::determinant(a)));
  if (!(s > 0) || !std::isfinite(s)) throw InputError("export: the animal frame (body/animal_frame.json) is degenerate");
  // The rotation nearest to the frame's columns, so a slightly skewed fit still exports rigidly.
  glm::dvec3 x = glm::normalize(a[0]), y = a[1] - glm::dot(a[1], x) * x;
  y = glm::normalize(y);
  const glm::dvec3 z = glm::cross(x, y);
  const glm::dmat3 r(x, y, z);  // animal axes in world coordinates
  ExportFrame f;
  f.metres_per_unit = cm_per_unit / 100.0;
  const glm::dvec3 origin(animal_to_world[3]);
  glm::dmat4 m(glm::dmat3(glm::transpose(r)) * f.metres_per_unit);
  m[3] = glm::dvec4(-(glm::transpose(r) * origin) * f.metres_per_unit, 1.0);
  double lowest = std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < body_world.vertex_count(); ++v) lowest = std::min(lowest, (m * glm::dvec4(glm::dvec3(body_world.position(v)), 1.0)).y);
  if (std::isfinite(lowest)) m[3].y -= lowest;
  f.world_to_export = m;
  return f;
}

geometry::Mesh to_export(const geometry::Mesh& mesh, const ExportFrame& frame) {
  geometry::Mesh out = mesh;
  geometry::transform_mesh(out, frame.world_to_export);
  return out;
}

}  // namespace nf::exporter
