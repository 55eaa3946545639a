#pragma once
// An envelope the user already has (a scan, another reconstruction) used as M_NeuS instead of a
// trained surface (`--set neus.mesh=FILE`). Read, checked against the visual hull of the scene's
// masks, which is what ties it to the scene's world frame and units, and turned to face outwards.
#include <cstdint>
#include <filesystem>

#include "engine/core/json.hpp"
#include "engine/geometry/mesh.hpp"
#include "engine/neus/visual_hull.hpp"

namespace nf::neus {

// A mesh whose surface lies inside the (slightly grown) hull less than this share of its area is
// in another frame or unit, or carries other geometry (a floor, a stand).
constexpr double kMinEnvelopeInsideHull = 0.9;
// The mesh box's diagonal over the hull box's: below, part of the animal or a smaller unit; above,
// geometry far beyond the masks or a larger unit.
constexpr double kMinEnvelopeExtentRatio = 0.5;
constexpr double kMaxEnvelopeExtentRatio = 1.5;

struct EnvelopeInputReport {
  std::uint64_t vertices = 0, triangles = 0;
  double inside_hull = 0;    // share of the surface area (by face centres) inside the hull grown by 2 cells
  double extent_ratio = 0;   // the mesh box's diagonal over the hull box's
  bool flipped = false;      // the faces pointed inwards (negative enclosed volume) and were turned
};
json to_json(const EnvelopeInputReport& report);

// The mesh of `file` (.ply, .obj, .glb, .gltf) with its per-vertex regions dropped, its faces
// facing outwards and, when it had normals, normals recomputed from that winding; fills
// report->vertices, triangles and flipped. InputError naming the file when it has no faces or
// non-finite vertices.
geometry::Mesh read_envelope_input(const std::filesystem::path& file, EnvelopeInputReport* report);

// The checks against the masks' visual hull above; fills report->inside_hull and extent_ratio.
// InputError naming the file with the measured value and what to fix.
void check_envelope_against_hull(const geometry::Mesh& mesh, const OccupancyGrid& hull, const std::filesystem::path& file,
                                 EnvelopeInputReport* report);

}  // namespace nf::neus
