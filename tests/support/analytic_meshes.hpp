#pragma once
// Closed test meshes from analytic signed distances (spheres, tori, unions), extracted with the
// CPU marching cubes: the shapes whose inside, distance and offsets the tests know exactly.
#include <algorithm>
#include <cmath>

#include "engine/geometry/marching_cubes.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "tests/support/scalar_grid.hpp"

namespace nf::test {

// The zero set of `sdf` over the cube [-extent, extent]^3 sampled every h.
template <class F>
geometry::Mesh mesh_of(F sdf, double extent, double h) {
  const int n = int(std::ceil(2 * extent / h)) + 1;
  const ScalarGrid g = sample_grid({n, n, n}, glm::vec3(float(-extent)), glm::vec3(float(h)), sdf);
  geometry::Mesh m = geometry::marching_cubes(g.values.data(), g.dims, g.origin, g.h, 0.f);
  return m;
}

inline double sphere_sdf(glm::dvec3 p, glm::dvec3 c, double r) { return glm::length(p - c) - r; }

// Two meshes as one (indices of the second shifted).
inline geometry::Mesh concatenate(const geometry::Mesh& a, const geometry::Mesh& b) {
  geometry::Mesh m = a;
  const std::uint32_t offset = std::uint32_t(a.vertex_count());
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  if (!a.normals.empty() && !b.normals.empty()) m.normals.insert(m.normals.end(), b.normals.begin(), b.normals.end());
  else m.normals.clear();
  if (!a.regions.empty() && !b.regions.empty()) m.regions.insert(m.regions.end(), b.regions.begin(), b.regions.end());
  else m.regions.clear();
  for (std::uint32_t v : b.triangles) m.triangles.push_back(v + offset);
  return m;
}

}  // namespace nf::test
