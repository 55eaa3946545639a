#pragma once
// The first step of the surface stage: a visual hull carved from the cameras' masks, the occupancy
// grid the NeuS sampler starts from (rays and samples only where the animal can be),
// and the scene normalisation that maps the hull into the unit sphere NeuS trains in.
//
// CPU code (threads over z-slabs via parallel_for). A GPU version can come later; the
// carve is a per-voxel, per-camera test with no dependencies, so it maps to one compute kernel.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/json.hpp"
#include "engine/io/scene.hpp"

namespace nf::neus {

// A box [lo, hi] split into dims.x * dims.y * dims.z cells, x fastest. Corners are double so that
// scenes far from the origin (1e3 units away) with small objects (1e-2 units) keep sub-cell
// precision.
struct OccupancyGrid {
  glm::dvec3 lo{0.0}, hi{0.0};
  glm::ivec3 dims{0};
  std::vector<std::uint8_t> occupied;  // 1 = the animal may be here

  glm::dvec3 cell_size() const { return (hi - lo) / glm::dvec3(dims); }
  std::size_t cell_count() const { return std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z); }
  std::size_t index(int i, int j, int k) const {
    return (std::size_t(k) * std::size_t(dims.y) + std::size_t(j)) * std::size_t(dims.x) + std::size_t(i);
  }
  glm::dvec3 cell_lo(int i, int j, int k) const { return lo + glm::dvec3(i, j, k) * cell_size(); }
  glm::dvec3 cell_centre(int i, int j, int k) const { return lo + (glm::dvec3(i, j, k) + 0.5) * cell_size(); }
  bool at(int i, int j, int k) const { return occupied[index(i, j, k)] != 0; }
  // The cell holding a world point; false when the point is outside the box.
  bool cell_of(const glm::dvec3& p, glm::ivec3& cell) const;
  // Whether the point's cell is occupied (false outside the box).
  bool contains(const glm::dvec3& p) const;
  std::size_t occupied_count() const;
  double occupied_fraction() const;                       // occupied / all cells (0 for an empty grid)
  double occupied_volume() const;                         // occupied cells x cell volume
  // The box spanned by the occupied cells (their full extents). Throws InternalError when none is.
  void occupied_bounds(glm::dvec3& box_lo, glm::dvec3& box_hi) const;
};

struct VisualHullOptions {
  int resolution = 128;         // cells along the longest axis of the final box (cells are cubes)
  int coarse_resolution = 64;   // cells along the longest axis while the box is being found
  int dilate_px = 2;            // masks are grown by this many pixels (square structuring element)
  int min_views = 2;            // a cell must be seen (centre in front of the camera, inside its image)
                                // by this many masked cameras (capped at their number)
  int margin_cells = 2;         // final box = occupied coarse cells grown by this many coarse cells
};

// Carves the visual hull of the scene's masks (io::mask_of of each camera's mask image).
//  - Cameras without a mask are skipped with a warning; if none has one: InputError naming the scene.
//  - A mask whose size is not the camera's: InputError naming the camera and the file.
//  - Start box: the cube around the least-squares closest point to all optical axes, half-size the
//    mean camera distance to that point (InputError when the axes are nearly parallel). Carved at
//    `coarse_resolution`, shrunk to the occupied cells + margin (repeated while it shrinks by more
//    than half), then carved at `resolution`.
//  - Full and partial views: a mask that touches no image border shows the whole object (a full
//    view), so cells projecting outside that image or lying behind that camera are carved, as in
//    the classic visual hull. A mask touching the border (the object cut off, a camera inside or
//    very close to the object) and an empty mask (a camera that sees nothing of the animal) make
//    a partial view: it carves only cells wholly in front of it whose projection lies wholly
//    inside its image.
//  - Conservative test: a camera carves a cell only when all 8 corners lie in front of it and no
//    pixel touched by the bounding rectangle of the 8 projected corners (which contains the
//    projected cube, a convex polytope) is set in the dilated mask. So a cell is kept when any
//    part of it may project into a mask pixel: thin parts (ears, tails, strands narrower than a
//    cell) survive. Cells straddling a camera's plane are never carved by it.
//  - An empty hull is an error: InputError naming the camera (and mask file) that carved most of
//    the cells every other camera kept, e.g. an all-zero mask.
OccupancyGrid carve_visual_hull(const io::Scene& scene, const VisualHullOptions& options = {});

// The grid grown by `cells` on every side (the box too, so nothing is clipped), each occupied cell
// marking its (2 cells + 1)^3 neighbourhood (Chebyshev distance <= cells). Slack for the sampler.
OccupancyGrid dilate(const OccupancyGrid& grid, int cells);

// unit = (world - centre) * scale; world = unit / scale + centre.
struct Normalisation {
  glm::dvec3 centre{0.0};
  double scale = 1.0;
  glm::dmat4 world_to_unit() const;
  glm::dmat4 unit_to_world() const;
  glm::dvec3 to_unit(const glm::dvec3& world) const { return (world - centre) * scale; }
  glm::dvec3 to_world(const glm::dvec3& unit) const { return unit / scale + centre; }
};

// centre = the centre of the box spanned by the hull's occupied cells; scale = 1 / (margin * h),
// h = half the box's diagonal. The box's corners land on the sphere of radius 1 / margin, so the
// whole hull (and everything it contains) lies inside the unit sphere. margin >= 1; InputError
// for an empty hull.
Normalisation normalise_to_unit_sphere(const OccupancyGrid& hull, double margin = 1.05);

// {"centre": [x, y, z], "scale": s}. The reader throws InputError naming `source` and the field.
json to_json(const Normalisation& n);
Normalisation normalisation_from_json(const json& j, const std::string& source);

}  // namespace nf::neus
