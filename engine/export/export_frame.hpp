#pragma once
// The frame the exported files share: the animal's own axes (+x its left, +y up, +z forward, which
// is glTF's convention and what Blender, Unreal and Houdini show upright), in metres, with the
// lowest point of the body on the ground plane y = 0 and the origin below the animal frame's
// origin. It is found from the data (the body fit's animal frame and the knowledge's metric scale),
// so a z-up scene in millimetres exports the same upright animal as a y-up one in metres.
// export.json records world_to_export so the files can be put back over the photos.
#include <glm/glm.hpp>

#include "engine/core/json.hpp"
#include "engine/geometry/mesh.hpp"

namespace nf::exporter {

struct ExportFrame {
  glm::dmat4 world_to_export{1.0};
  double metres_per_unit = 1.0;  // scene units -> metres

  glm::vec3 point(const glm::vec3& world) const { return glm::vec3(world_to_export * glm::dvec4(glm::dvec3(world), 1.0)); }
  // Directions and normals (the map is a rotation times a uniform scale): unit length kept.
  glm::vec3 direction(const glm::vec3& world) const;
  json to_json() const;
};

// `animal_to_world`: columns left, up, forward (scaled alike) and the origin, as the body stage
// writes it; `body_world`: the mesh whose lowest point goes to y = 0. InputError when the frame is
// degenerate or the scale is not positive.
ExportFrame export_frame(const glm::dmat4& animal_to_world, double cm_per_unit, const geometry::Mesh& body_world);

// A copy of `mesh` in the export frame (positions, normals).
geometry::Mesh to_export(const geometry::Mesh& mesh, const ExportFrame& frame);

}  // namespace nf::exporter
