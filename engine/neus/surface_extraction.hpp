#pragma once
// The surface stage's mesh: the SDF sampled on a grid over the (dilated) visual hull's box, with
// the resolution given along the box's longest axis (cells are cubes, so the grid follows the
// scene's extent), only at grid points inside the hull (others are outside by construction),
// then marching cubes on the GPU, the largest component; vertex normals from the grid's central
// differences (one-sided next to the constant outside values).
// Positions in scene units.
#include "engine/io/mesh.hpp"
#include "engine/neus/neus_field.hpp"
#include "engine/neus/visual_hull.hpp"

namespace nf::neus {

struct SurfaceGridStats {
  glm::ivec3 dims{0};
  std::uint64_t evaluated = 0;  // grid points the network was asked about
  std::uint64_t components = 0;  // connected components before the largest was kept
};

geometry::Mesh extract_surface(const NeusField& field, const Normalisation& norm, const OccupancyGrid& hull, int resolution,
                         SurfaceGridStats* stats = nullptr);

// The occupancy grid's own surface (marching cubes of +-1 at cell centres): the visual hull as a
// mesh, the baseline the trained surface is compared with.
geometry::Mesh hull_surface(const OccupancyGrid& hull);

}  // namespace nf::neus
