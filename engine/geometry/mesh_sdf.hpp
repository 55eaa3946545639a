#pragma once
// A triangle mesh to a signed distance grid whose sign survives real meshes: small holes, thin
// sheets, self-touching or overlapping parts, duplicated or inconsistent faces.
//
// Sign: the winding number along grid lines. For each axis, every grid line parallel to it is
// intersected with every triangle (an exact, watertight fill rule on the lattice: each lattice
// point on an edge or vertex shared by triangles is counted once), and each crossing adds +1 when
// the line enters the solid (crosses from the triangle's front to its back) and -1 when it leaves. The running
// sum along the line is the winding number at each sample: non-zero is inside, so overlapping parts
// (winding 2) stay inside and inverted meshes (winding -1) work too. A line whose sum does not
// return to 0 at its end passed through a hole (or a stray face): it casts no vote. Each sample
// takes the majority of the three axes' votes; a tie (rare: next to holes) is settled by the
// closest triangle's side within the band and "outside" beyond it.
//
// Distance: exact point-to-triangle distance in a band around the surface, by closest-triangle
// propagation (each triangle seeds the samples around it, then sweeps along x, y and z hand every
// sample its neighbours' closest triangles, re-measured exactly). Beyond the band the magnitude is
// clamped to the band: only the surface's neighbourhood is modelled; the interior is marked by the
// sign.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/geometry/mesh.hpp"

namespace nf::geometry {

// A regular grid of samples: sample (i, j, k) lies at origin + voxel * (i, j, k); x fastest.
struct GridSpec {
  glm::ivec3 dims{0};
  glm::vec3 origin{0.f};
  float voxel = 0;
  std::size_t size() const { return std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z); }
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(k) * std::size_t(dims.y) + std::size_t(j)) * std::size_t(dims.x) + std::size_t(i);
  }
  glm::vec3 position(int i, int j, int k) const { return origin + voxel * glm::vec3(i, j, k); }
};

// The grid over the box [lo, hi] with `resolution` samples along its longest side, grown by
// `padding` (scene units) on every side. InputError for an empty or non-finite box or resolution < 2.
GridSpec grid_around(glm::vec3 lo, glm::vec3 hi, int resolution, float padding);

inline constexpr std::uint32_t kNoTriangle = 0xffffffffu;

struct SignStats {
  std::uint64_t lines = 0, open_lines = 0;  // grid lines over all three axes; lines whose winding did not close
  std::uint64_t tied_samples = 0;          // samples whose votes tied
};

struct SignedDistanceGrid {
  GridSpec grid;
  float band = 0;                             // exact distances within it (scene units)
  std::vector<float> distance;                // negative inside; |d| clamped to `band`
  std::vector<std::uint32_t> closest;         // the closest triangle within the band, else kNoTriangle
  SignStats sign;
};

struct SdfOptions {
  int resolution = 256;  // samples along the mesh's longest side
  float band = 0;        // scene units; 0: 3 voxels
  float padding = -1;    // scene units around the mesh's box; < 0: the band plus 2 voxels
};

// InputError naming `source` for a mesh without triangles, with NaN/Inf positions or bad indices.
SignedDistanceGrid signed_distance_grid(const Mesh& mesh, const SdfOptions& options, const std::string& source);

// The sign alone: 1 where the sample is inside by the winding vote, 0 outside, 2 where the votes tied.
std::vector<std::uint8_t> winding_inside(const Mesh& mesh, const GridSpec& grid, SignStats* stats = nullptr);

// Trilinear interpolation of grid values at a point (clamped to the grid).
float sample_grid(const GridSpec& grid, const std::vector<float>& values, glm::vec3 p);

}  // namespace nf::geometry
