#include "engine/synth/world_frame.hpp"

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "engine/geometry/mesh_tools.hpp"

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

void transform_strands(const WorldFrame& frame, io::StrandSet& strands) {
  geometry::transform_points(strands.points, frame.matrix());
  for (float& t : strands.thickness) t = float(t * frame.scale);
}

void transform_camera(const WorldFrame& frame, io::Camera& camera) {
  glm::dmat4& m = camera.camera_to_world;
  for (int c = 0; c < 3; ++c) m[c] = glm::dvec4(frame.direction(glm::dvec3(m[c])), 0.0);
  m[3] = glm::dvec4(frame.point(glm::dvec3(m[3])), 1.0);
}

}  // namespace nf::synth
