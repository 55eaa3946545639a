#pragma once
// Small triangle-mesh utilities: connected components, vertex normals, the bounding box, a
// closed-manifold check, a change of frame.
#include <algorithm>
#include <cstddef>

#include <glm/glm.hpp>

#include "engine/geometry/mesh.hpp"

namespace nf::geometry {

// Keeps the connected component (triangles joined through shared vertices) with the most
// triangles; ties go to the component of the lowest-numbered triangle. Vertices no kept triangle
// uses are dropped (kept vertices stay in their order); normals and regions follow their vertices.
// A mesh without triangles ends up empty. Returns the number of components found.
std::size_t keep_largest_component(geometry::Mesh& mesh);

// Replaces mesh.normals by area-weighted vertex normals (the sum of the incident faces' cross
// products, normalised). A vertex without any face of non-zero area gets (0, 0, 0).
void compute_vertex_normals(geometry::Mesh& mesh);

// The box of a mesh's vertices (lo = hi = 0 for a mesh without vertices).
struct Bounds {
  glm::vec3 lo{0.f}, hi{0.f};
  glm::vec3 extent() const { return hi - lo; }
  float longest() const { return std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}); }
  float diagonal() const { return glm::length(hi - lo); }
};
Bounds mesh_bounds(const geometry::Mesh& mesh);
// Each vertex's area: a third of its triangles' areas (what area-weighted shares of a surface sum).
std::vector<double> vertex_areas(const geometry::Mesh& mesh);
// True when every undirected edge is used by exactly two triangles, once in each direction
// (consistent orientation), no triangle repeats a vertex, and the triangles around every used
// vertex form a single fan (no pinched vertices). An empty mesh is closed.
bool is_closed_manifold(const geometry::Mesh& mesh);

// A change of frame by a similarity (rotation times a uniform scale, then a translation): xyz
// triples in place; a mesh's positions, and its normals turned by the rotation (unit length kept).
void transform_points(std::vector<float>& xyz, const glm::dmat4& similarity);
void transform_mesh(geometry::Mesh& mesh, const glm::dmat4& similarity);

}  // namespace nf::geometry
