#pragma once
// Exact Euclidean distance transform of a 3D mask (Felzenszwalb & Huttenlocher, "Distance
// Transforms of Sampled Functions": 1D lower envelopes of parabolas along x, then y, then z).
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace nf::geometry {

// mask: dims.x * dims.y * dims.z entries, x fastest; non-zero marks a feature voxel. Returns, per
// voxel, the distance in world units (voxel_size per axis, anisotropic allowed) from its centre to
// the nearest feature voxel's centre: 0 on features, +infinity everywhere when there is no feature.
// Throws InputError for negative dims, a mask of the wrong size, or a non-positive or non-finite
// voxel size. Lines run in parallel.
std::vector<float> distance_transform(const std::vector<std::uint8_t>& mask, glm::ivec3 dims,
                                      glm::vec3 voxel_size = glm::vec3(1.f));

}  // namespace nf::geometry
