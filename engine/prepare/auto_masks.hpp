#pragma once
// Masks made without a hand, for photos whose cameras COLMAP found. The animal is what every camera
// looks at and stands on the floor (scene_layout.hpp: its sparse points stand above the floor near
// where the cameras aim; floor and far points are background). Each photo is segmented by a graph cut on colour
// (OpenCV's GrabCut), bounded by the animal's box and seeded by where that photo observed animal and
// background points and by what the other photos say of its floor (floor_consistency.hpp: the legs
// and the body seen against the floor stand out, the floor and shadows on it agree); then the masks
// are made to agree across views: a visual hull is carved from them, projected back, and each photo
// is cut again inside it, and its outline moved onto the photo's colour edges (mask_outline.hpp). A view whose first cut fits the others' silhouette only once moved, or
// whose final mask leaves out most of its own keypoints on the animal (keypoint_cover.hpp), has a
// wrong pose and is left out.
#include <cstdint>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/io/scene.hpp"
#include "engine/prepare/photo_mats.hpp"
#include "engine/prepare/scene_layout.hpp"
#include "engine/prepare/sparse_points.hpp"

namespace nf::prepare {

struct AutoMaskOptions {
  std::uint32_t rounds = 2;             // cuts per photo: the first alone, then each inside the hull of the last
  std::uint32_t hull_cells = 160;       // the visual hull's voxels along the animal box's longest side
  std::uint32_t grabcut_iterations = 5;
  // The cuts, the floor's evidence and the hull work on the photos reduced to this many pixels on
  // their longer side; the final masks are drawn back at the photo's own size and their outlines
  // snapped to its edges there.
  std::uint32_t working_side = kWorkingSide;
};

struct AutoMasks {
  std::vector<std::vector<std::uint8_t>> masks;  // per camera of the scene, width x height, 1 = animal
  json report;  // the centre, floor and animal points found, and per view its share of animal and its agreement with the hull
  // Views whose first cut meets the others' silhouette only when moved (silhouette_check.hpp), or
  // whose mask misses their own keypoints on the animal: their pose is wrong. In ascending order;
  // the caller leaves them out of the scene.
  std::vector<StrayCamera> misplaced;
};

// The scene's cameras must be undistorted pinholes with their photos (of any size: see working_side); `points` and `layout` from the
// same model (scene_layout.hpp finds the centre, the floor and the animal's points).
// Throws InputError when too few sparse points stand above the floor to say where the animal is.
AutoMasks automatic_masks(const io::Scene& scene, const SparsePoints& points, const SceneLayout& layout, const AutoMaskOptions& options = {});

}  // namespace nf::prepare
