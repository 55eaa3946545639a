#pragma once
// A pose COLMAP got a little wrong (a photo matched to the wrong copy of a repeating pattern: a
// fraction of the animal's size off, a few degrees turned) still aims at the animal, so
// stray_cameras keeps it, and its reprojection error is small (its matches agree with the wrong
// pose). What gives it away is the animal its photo shows: not where the views' silhouettes put it.
// Each view's mask is compared with the visual hull the views carve together (its own among them),
// drawn back into that view; the carving is tolerant (a fifth of the views may miss a voxel, at
// least one), so a wrong view among ten or more does not carve the others. Where a view disagrees,
// sliding its mask over the drawn hull tells a wrong pose (the mask fits once moved) from a wrong
// mask (it fits nowhere). Both are compared reduced to 160 px on the longer side.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/io/scene.hpp"
#include "engine/prepare/scene_layout.hpp"

namespace nf::prepare {

struct SilhouetteOptions {
  std::uint32_t cells = 96;  // the hull's voxels along the box's longest side
  double max_shift = 0.2;    // how far a mask is slid, as a share of the photo's longer side
  // The least slide that refutes a pose, as a share of the photo's longer side: COLMAP's poses at
  // a few hundred pixels scatter by a few pixels, which a drawn-back hull cannot tell from the
  // hull's own fat; a tenth of the animal's radius off moves a 192 px photo's animal 10 px.
  double min_shift = 0.04;
};

struct ViewSilhouette {
  double iou = 0;          // the view's mask against the hull drawn back into it (reduced to 160 px)
  double shifted_iou = 0;  // the best IoU over slides of the mask
  double shift_px = 0;     // the slide that gives it, in photo pixels
  bool misplaced = false;  // the mask fits the hull once moved: the pose is wrong
  bool disagrees = false;  // it fits nowhere: the mask or the photo is to be checked
  bool left_out = false;   // refuted before (by the floor): no part in the hull, not judged
};

struct SilhouetteCheck {
  std::vector<ViewSilhouette> views;  // per camera
  double median_iou = 0;
  std::size_t hull_voxels = 0;  // 0: the views share no volume, and nothing is concluded
  json report(const std::vector<io::Camera>& cameras) const;
  // Why the pose of view i is refuted, for the user (empty unless misplaced).
  std::string reason(std::size_t i) const;
};

// `masks`: per camera, width x height, non-zero where the animal is. `box` bounds the animal.
// `left_out` (when given): views whose pose is already refuted; they neither carve nor are judged.
SilhouetteCheck check_silhouettes(const std::vector<io::Camera>& cameras, const std::vector<std::vector<std::uint8_t>>& masks,
                                  const AnimalBox& box, const SilhouetteOptions& options = {}, const std::vector<char>* left_out = nullptr);

}  // namespace nf::prepare
