#pragma once
// Small triangle-mesh utilities: connected components, vertex normals, a closed-manifold check.
#include <cstddef>

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

// True when every undirected edge is used by exactly two triangles, once in each direction
// (consistent orientation), no triangle repeats a vertex, and the triangles around every used
// vertex form a single fan (no pinched vertices). An empty mesh is closed.
bool is_closed_manifold(const geometry::Mesh& mesh);

}  // namespace nf::geometry
