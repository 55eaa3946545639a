#include "engine/neus/surface_extraction.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/error.hpp"
#include "engine/geometry/marching_cubes.hpp"
#include "engine/geometry/marching_cubes_gpu.hpp"
#include "engine/geometry/mesh_tools.hpp"

namespace nf::neus {

geometry::Mesh extract_surface(const NeusField& field, const Normalisation& norm, const OccupancyGrid& hull, int resolution,
                         SurfaceGridStats* stats) {
  if (resolution < 8 || resolution > 2048)
    throw InputError("surface extraction: resolution must be in [8, 2048], got " + std::to_string(resolution));
  const glm::dvec3 extent = hull.hi - hull.lo;
  const double voxel = std::max({extent.x, extent.y, extent.z}) / resolution;
  // One sample of padding on every side, outside by construction, closes the surface.
  glm::ivec3 dims;
  for (int a = 0; a < 3; ++a) dims[a] = int(std::ceil(extent[a] / voxel)) + 3;
  const glm::dvec3 origin = hull.lo - voxel;
  const std::size_t count = std::size_t(dims.x) * dims.y * dims.z;
  constexpr float kOutside = 1.f;  // unit coordinates: farther than any surface point can be
  std::vector<float> values(count, kOutside);
  std::vector<glm::vec3> points;
  std::vector<std::size_t> where;
  for (int k = 1; k + 1 < dims.z; ++k)
    for (int j = 1; j + 1 < dims.y; ++j)
      for (int i = 1; i + 1 < dims.x; ++i) {
        const glm::dvec3 p = origin + glm::dvec3(i, j, k) * voxel;
        if (!hull.contains(p)) continue;
        points.push_back(glm::vec3(norm.to_unit(p)));
        where.push_back((std::size_t(k) * dims.y + j) * dims.x + i);
      }
  const std::vector<float> sdf = field.sdf_at(points);
  for (std::size_t i = 0; i < sdf.size(); ++i) values[where[i]] = std::isfinite(sdf[i]) ? sdf[i] : kOutside;
  geometry::Mesh mesh = geometry::marching_cubes_gpu(field.context(), values, dims, glm::vec3(origin), glm::vec3(float(voxel)), 0.f);
  const std::size_t components = geometry::keep_largest_component(mesh);  // normals follow their vertices
  if (stats) *stats = {dims, points.size(), components};
  return mesh;
}

geometry::Mesh hull_surface(const OccupancyGrid& hull) {
  const glm::ivec3 dims = hull.dims + 2;  // a layer of empty cells all round closes the surface
  std::vector<float> values(std::size_t(dims.x) * dims.y * dims.z, 1.f);
  for (int k = 0; k < hull.dims.z; ++k)
    for (int j = 0; j < hull.dims.y; ++j)
      for (int i = 0; i < hull.dims.x; ++i)
        if (hull.at(i, j, k)) values[(std::size_t(k + 1) * dims.y + (j + 1)) * dims.x + (i + 1)] = -1.f;
  const glm::dvec3 cs = hull.cell_size();
  return geometry::marching_cubes(values.data(), dims, glm::vec3(hull.lo - 0.5 * cs), glm::vec3(cs), 0.f);
}

}  // namespace nf::neus
