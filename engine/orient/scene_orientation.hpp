#pragma once
// Orientation maps for the views of a scene (`nf_gpu orient`): per view, <name>.exr (R orientation,
// G confidence) and <name>.png (hue = doubled angle, value = confidence), inside the view's mask
// when it has one; on a synth scene with true orientation maps, how far each map agrees with them. The fur stage computes the same maps once and caches them.
#include <filesystem>
#include <string>
#include <vector>

#include "engine/gpu/context.hpp"
#include "engine/orient/gabor_bank.hpp"
#include "engine/orient/orientation_truth.hpp"

namespace nf::orient {

struct SceneOrientationOptions {
  std::filesystem::path scene, out;
  std::string views = "all";  // "all" or indices like 0,5,9
  GaborParams gabor;
  std::uint32_t reliability_window = 9;  // the fur stage's fur.coherence window (fur_views.hpp)
};

struct ViewTruthAgreement {
  std::string camera;
  TruthAgreement agreement;
};

struct SceneOrientations {
  std::vector<std::filesystem::path> files;
  // On a synth scene made with --true-orientation: each view's map against its true orientation
  // (orientation_truth.hpp), its reliability over `reliability_window` pixels as the fur stage's.
  std::vector<ViewTruthAgreement> truth;
};

// The output folder is created (never inside the scene); only <name>.exr / <name>.png (and with a
// truth, truth_agreement.json) are written, and no file that nf_gpu did not write is replaced.
SceneOrientations write_scene_orientations(gpu::Context& context, const SceneOrientationOptions& options);

}  // namespace nf::orient
