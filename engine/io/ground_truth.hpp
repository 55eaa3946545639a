#pragma once
// The ground truth an `nf_gpu synth` scene carries in SCENE/gt/ (strands, bald body, fur
// envelope, knowledge, and gt/scene.json with the scene's unit in cm). Stages and
// `nf_gpu metrics` compare against it when it is there; real scenes have none.
#include <filesystem>
#include <optional>
#include <string>

#include "engine/core/json.hpp"

namespace nf::io {

struct GroundTruth {
  std::filesystem::path dir;  // SCENE/gt
  json info;                  // gt/scene.json
  double cm_per_unit = 0;

  std::filesystem::path scene_json() const { return dir / "scene.json"; }
  std::filesystem::path outer() const { return dir / "outer.ply"; }      // the fur envelope
  std::filesystem::path bald() const { return dir / "bald.ply"; }        // the body, region per vertex
  std::filesystem::path strands() const { return dir / "strands.hair"; }
  std::filesystem::path knowledge() const { return dir / "knowledge.json"; }
  // The true orientation map of a camera's photo (synth --true-orientation), when it was written.
  std::filesystem::path orientation(const std::string& camera) const { return dir / "orientation" / (camera + ".exr"); }
};

// nullopt when `scene_dir`/gt/scene.json does not exist; InputError naming the file when it exists
// but is not JSON or lacks a positive cm_per_unit.
std::optional<GroundTruth> find_ground_truth(const std::filesystem::path& scene_dir);

}  // namespace nf::io
