#pragma once
// The closest point of a triangle mesh to query points near it (roots on the skin, vertices of a
// surface that follows another): the faces around the query's k nearest vertices are tested
// exactly (closest_point.hpp). That is exact whenever the closest face has one of those vertices,
// which holds for points on or close to a surface of reasonable triangles; it is not a general
// distance query for points far from the mesh. Queries are const and thread-safe.
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "engine/geometry/mesh.hpp"
#include "engine/geometry/point_index.hpp"

namespace nf::geometry {

struct SurfaceHit {
  std::uint32_t face = 0;
  glm::vec3 barycentric{1, 0, 0};  // of the face's three vertices
  glm::vec3 point{0};
  float distance = 0;
};

class SurfaceLocator {
 public:
  // `mesh` must outlive the locator and have at least one triangle.
  explicit SurfaceLocator(const Mesh& mesh, std::size_t candidate_vertices = 8);
  SurfaceHit closest(const glm::vec3& query) const;

 private:
  const Mesh& mesh_;
  std::size_t k_;
  PointIndex index_;
  std::vector<std::uint32_t> face_start_, faces_;  // faces around each vertex (CSR)
};

}  // namespace nf::geometry
