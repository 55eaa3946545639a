#pragma once
// A scalar field sampled on a regular grid (x fastest), as the marching-cubes suites feed it.
#include <cmath>
#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

namespace nf::test {

struct ScalarGrid {
  std::vector<float> values;
  glm::ivec3 dims;
  glm::vec3 origin, h;
  glm::vec3 at(int x, int y, int z) const { return origin + glm::vec3(float(x), float(y), float(z)) * h; }
};

// field(glm::dvec3 position) at every grid point.
template <class F>
ScalarGrid sample_grid(glm::ivec3 dims, glm::vec3 origin, glm::vec3 h, F field) {
  ScalarGrid g{{}, dims, origin, h};
  g.values.reserve(std::size_t(dims.x) * dims.y * dims.z);
  for (int z = 0; z < dims.z; ++z)
    for (int y = 0; y < dims.y; ++y)
      for (int x = 0; x < dims.x; ++x) g.values.push_back(float(field(glm::dvec3(g.at(x, y, z)))));
  return g;
}

// Signed distance to a torus around the y axis: major radius R, tube radius r.
inline double torus_sdf(glm::dvec3 p, double R, double r) {
  const double q = std::sqrt(p.x * p.x + p.z * p.z) - R;
  return std::sqrt(q * q + p.y * p.y) - r;
}

}  // namespace nf::test
