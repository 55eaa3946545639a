#pragma once
// Orientation maps for the views of a scene (`nf_gpu orient`): per view, <name>.exr (R orientation,
// G confidence) and <name>.png (hue = doubled angle, value = confidence), inside the view's mask
// when it has one. The fur stage computes the same maps once and caches them.
#include <filesystem>
#include <string>
#include <vector>

#include "engine/gpu/context.hpp"
#include "engine/orient/gabor_bank.hpp"

namespace nf::orient {

struct SceneOrientationOptions {
  std::filesystem::path scene, out;
  std::string views = "all";  // "all" or indices like 0,5,9
  GaborParams gabor;
};

// Returns the files written. The output folder is created (never inside the scene); only
// <name>.exr / <name>.png are written, and no file that nf_gpu did not write is replaced.
std::vector<std::filesystem::path> write_scene_orientations(gpu::Context& context, const SceneOrientationOptions& options);

}  // namespace nf::orient
