#include "engine/geometry/surface_locator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/core/error.hpp"
#include "engine/geometry/closest_point.hpp"

namespace nf::geometry {

SurfaceLocator::SurfaceLocator(const Mesh& mesh, std::size_t candidate_vertices)
    : mesh_(mesh), k_(std::max<std::size_t>(1, candidate_vertices)), index_(mesh.positions) {
  if (mesh.triangle_count() == 0) throw InputError("surface locator: the mesh has no triangles");
  face_start_.assign(mesh.vertex_count() + 1, 0);
  for (std::uint32_t v : mesh.triangles) ++face_start_[v + 1];
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) face_start_[v + 1] += face_start_[v];
  faces_.resize(mesh.triangles.size());
  std::vector<std::uint32_t> fill(face_start_.begin(), face_start_.end() - 1);
  for (std::size_t f = 0; f < mesh.triangle_count(); ++f)
    for (int c = 0; c < 3; ++c) faces_[fill[mesh.triangles[3 * f + std::size_t(c)]]++] = std::uint32_t(f);
}

SurfaceHit SurfaceLocator::closest(const glm::vec3& q) const {
  SurfaceHit best;
  float best_d2 = std::numeric_limits<float>::infinity();
  bool any = false;
  for (std::uint32_t v : index_.nearest_k(&q.x, k_))
    for (std::uint32_t i = face_start_[v]; i < face_start_[v + 1]; ++i) {
      const std::uint32_t f = faces_[i];
      const std::uint32_t* t = &mesh_.triangles[3 * std::size_t(f)];
      const TrianglePoint cp = closest_point_on_triangle(q, mesh_.position(t[0]), mesh_.position(t[1]), mesh_.position(t[2]));
      const glm::vec3 d = cp.point - q;
      const float d2 = glm::dot(d, d);
      if (d2 < best_d2) best_d2 = d2, best = {f, cp.barycentric, cp.point, 0.f}, any = true;
    }
  if (!any) {  // isolated nearest vertices: fall back to every face (rare; correct, slow)
    for (std::uint32_t f = 0; f < mesh_.triangle_count(); ++f) {
      const std::uint32_t* t = &mesh_.triangles[3 * std::size_t(f)];
      const TrianglePoint cp = closest_point_on_triangle(q, mesh_.position(t[0]), mesh_.position(t[1]), mesh_.position(t[2]));
      const float d2 = glm::dot(cp.point - q, cp.point - q);
      if (d2 < best_d2) best_d2 = d2, best = {f, cp.barycentric, cp.point, 0.f};
    }
  }
  best.distance = std::sqrt(best_d2);
  return best;
}

}  // namespace nf::geometry
