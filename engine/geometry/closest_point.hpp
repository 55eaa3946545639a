#pragma once
// The point of a triangle closest to a query point, with its barycentric coordinates: exact
// distances for signed-distance grids and for transferring per-vertex values to nearby points.
#include <glm/glm.hpp>

namespace nf::geometry {

struct TrianglePoint {
  glm::vec3 point;        // the closest point
  glm::vec3 barycentric;  // weights of a, b, c (non-negative, summing to 1)
};

// Voronoi-region walk over the triangle's vertices, edges and interior (Ericson, "Real-Time
// Collision Detection", 5.1.5). A degenerate triangle falls back to its closest vertex or edge.
TrianglePoint closest_point_on_triangle(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c);

}  // namespace nf::geometry
