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

// A mesh whose vertices fall inside the (slightly grown) hull less often than this is in another
// frame or unit, or carries other geometry (a floor, a stand).
constexpr double kMinEnvelopeInsideHull = 0.9;
// A mesh whose box is less than this share of the hull's box diagonal covers only part of the
// animal, or is in a smaller unit.
constexpr double kMinEnvelopeExtentRatio = 0.5;

struct EnvelopeInputReport {
  std::uint64_t vertices = 0, triangles = 0;
  double inside_hull = 0;    // share of vertices inside the hull grown by 2 cells
  double extent_ratio = 0;   // the mesh box's diagonal over the hull box's
  bool flipped = false;      // the faces pointed inwards (negative enclosed volume) and were turned
};
json to_json(const EnvelopeInputReport& report);

// The mesh of `file` (.ply, .obj, .glb, .gltf) with its per-vertex regions dropped and its faces
// facing outwards. InputError naming the file when it has no faces, non-finite vertices, or fails
// either check above (the message gives the measured share and what to fix).
geometry::Mesh read_envelope_input(const std::filesystem::path& file, const OccupancyGrid& hull, EnvelopeInputReport* report);

}  // namespace nf::neus
