#pragma once
// Iso-surface extraction from a scalar grid (marching cubes with the generated table of
// marching_cubes_table.hpp: watertight, consistent ambiguity rule).
#include <glm/glm.hpp>

#include "engine/geometry/mesh.hpp"

namespace nf::geometry {

// values: dims.x * dims.y * dims.z samples, x fastest; sample (i,j,k) lies at
// origin + (i,j,k) * voxel_size. "Inside" is value < iso, outside value >= iso.
// Returns a welded mesh: one vertex per grid edge that crosses the iso-value (shared by the cubes
// around it), placed by linear interpolation, with unit normals from the central-difference
// gradient of the field (one-sided at the grid's border) pointing to increasing values, and
// triangles wound so that their right-hand normal points the same way. Wherever the field is
// inside at the grid's border the surface is open there: pad with outside values for a closed mesh.
// Throws InputError for negative dims, a non-positive or non-finite voxel size, a non-finite iso,
// and for any NaN or Inf sample (naming its index). A grid thinner than 2 samples gives an empty mesh.
// Runs over z-slabs in parallel; the result does not depend on the thread count.
geometry::Mesh marching_cubes(const float* values, glm::ivec3 dims, glm::vec3 origin, glm::vec3 voxel_size, float iso = 0.f);

}  // namespace nf::geometry
