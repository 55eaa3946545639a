#pragma once
// Points sampled uniformly over a triangle mesh's area (seeded), with the normal of the face each
// lies on: the common ground of surface metrics.
#include <cstdint>
#include <vector>

#include "engine/geometry/mesh.hpp"

namespace nf::geometry {

struct SurfaceSamples {
  std::vector<float> points;   // xyz
  std::vector<float> normals;  // unit face normals, xyz
};

// Degenerate (zero-area) faces are never chosen; a mesh without area gives no samples.
SurfaceSamples sample_surface(const geometry::Mesh& mesh, std::uint64_t count, unsigned seed);

}  // namespace nf::geometry
