#include "engine/export/pose_groom.hpp"

#include <cmath>

#include "engine/body/body_model.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/mesh_tools.hpp"

namespace nf::exporter {
namespace {

glm::mat4 translation(const glm::vec3& t) {
  glm::mat4 m(1.f);
  m[3] = glm::vec4(t, 1.f);
  return m;
}

// Orthonormal frame of a triangle: first edge, in-plane perpendicular, normal (columns).
glm::mat3 face_frame(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const glm::vec3 e = b - a;
  const glm::vec3 n = glm::cross(e, c - a);
  if (glm::length(e) == 0.f || glm::length(n) == 0.f) return glm::mat3(1.f);
  const glm::vec3 x = glm::normalize(e), z = glm::normalize(n);
  return glm::mat3(x, glm::cross(z, x), z);
}

}  // namespace

std::vector<glm::mat4> skinning_transforms(const io::Skeleton& s, const std::vector<glm::vec3>& rotations) {
  const std::size_t J = s.joint_count();
  std::vector<glm::mat4> global(J), skin(J);
  for (std::size_t j = 0; j < J; ++j) {
    const int parent = s.parents[j];
    const glm::vec3 offset = s.joint_positions[j] - (parent < 0 ? glm::vec3(0.f) : s.joint_positions[std::size_t(parent)]);
    const glm::mat4 local = translation(offset) * (j < rotations.size() ? body::rotation_from_axis_angle(rotations[j]) : glm::mat4(1.f));
    global[j] = parent < 0 ? local : global[std::size_t(parent)] * local;
    skin[j] = global[j] * translation(-s.joint_positions[j]);
  }
  return skin;
}

geometry::Mesh skin_mesh(const geometry::Mesh& rest, const io::Skeleton& s, const std::vector<glm::mat4>& skinning) {
  geometry::Mesh out = rest;
  parallel_for(rest.vertex_count(), [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      glm::mat4 m(0.f);
      for (int k = 0; k < io::kJointInfluences; ++k) {
        const float w = s.skin_weights[io::kJointInfluences * v + std::size_t(k)];
        if (w > 0) m += w * skinning[s.skin_joints[io::kJointInfluences * v + std::size_t(k)]];
      }
      const glm::vec3 p = glm::vec3(m * glm::vec4(rest.position(v), 1.f));
      for (int a = 0; a < 3; ++a) out.positions[3 * v + std::size_t(a)] = p[a];
    }
  });
  if (!rest.normals.empty()) geometry::compute_vertex_normals(out);
  return out;
}

RootMotion root_motion(const geometry::Mesh& rest, const geometry::Mesh& posed, std::uint32_t face, const glm::vec3& b) {
  const std::uint32_t* t = &rest.triangles[3 * std::size_t(face)];
  const auto at = [&](const geometry::Mesh& m) { return b.x * m.position(t[0]) + b.y * m.position(t[1]) + b.z * m.position(t[2]); };
  RootMotion r;
  r.from = at(rest), r.to = at(posed);
  r.rotation = face_frame(posed.position(t[0]), posed.position(t[1]), posed.position(t[2])) *
               glm::transpose(face_frame(rest.position(t[0]), rest.position(t[1]), rest.position(t[2])));
  return r;
}

}  // namespace nf::exporter
