#include "engine/synth/world_frame.hpp"

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"

namespace nf::synth {

glm::dmat4 WorldFrame::matrix() const {
  glm::dmat4 m(scale * rotation);
  m[3] = glm::dvec4(offset, 1.0);
  return m;
}

std::vector<std::string> world_frame_names() { return {"y-up-m", "z-up-mm"}; }

WorldFrame world_frame(const std::string& name) {
  WorldFrame f;
  f.name = name;
  if (name == "y-up-m") return f;
  if (name == "z-up-mm") {
    // +90 degrees about x: y (up) -> z, z -> -y. Columns are the images of the axes.
    f.rotation = glm::dmat3(glm::dvec3(1, 0, 0), glm::dvec3(0, 0, 1), glm::dvec3(0, -1, 0));
    f.scale = 1000.0;
    f.offset = glm::dvec3(1500.0, -2500.0, 400.0);  // metres away: nothing may assume the origin is near
    return f;
  }
  throw UsageError("synth: unknown --frame '" + name + "' (" + join(world_frame_names()) + ")");
}

void transform_mesh(const WorldFrame& frame, geometry::Mesh& mesh) {
  for (std::size_t i = 0; i + 2 < mesh.positions.size(); i += 3) {
    const glm::dvec3 p = frame.point({mesh.positions[i], mesh.positions[i + 1], mesh.positions[i + 2]});
    for (int a = 0; a < 3; ++a) mesh.positions[i + std::size_t(a)] = float(p[a]);
  }
  for (std::size_t i = 0; i + 2 < mesh.normals.size(); i += 3) {
    const glm::dvec3 n = frame.direction({mesh.normals[i], mesh.normals[i + 1], mesh.normals[i + 2]});
    for (int a = 0; a < 3; ++a) mesh.normals[i + std::size_t(a)] = float(n[a]);
  }
}

void transform_strands(const WorldFrame& frame, io::StrandSet& strands) {
  for (std::size_t i = 0; i + 2 < strands.points.size(); i += 3) {
    const glm::dvec3 p = frame.point({strands.points[i], strands.points[i + 1], strands.points[i + 2]});
    for (int a = 0; a < 3; ++a) strands.points[i + std::size_t(a)] = float(p[a]);
  }
  for (float& t : strands.thickness) t = float(t * frame.scale);
}

void transform_camera(const WorldFrame& frame, io::Camera& camera) {
  glm::dmat4& m = camera.camera_to_world;
  for (int c = 0; c < 3; ++c) m[c] = glm::dvec4(frame.direction(glm::dvec3(m[c])), 0.0);
  m[3] = glm::dvec4(frame.point(glm::dvec3(m[3])), 1.0);
}

}  // namespace nf::synth
