#pragma once
// A batch manifest: the scenes to reconstruct, each with its WORK folder and its own settings over
// a shared default. Two forms:
//   JSON  [{"scene": "cats/tom", "work": "out/tom", "settings": {"fur.steps": 300}}, ...]
//         or {"defaults": {"quality": "draft", "settings": {...}}, "scenes": [...]}; a scene may
//         also give "name", "quality" and "scene_scale" (cm per scene unit);
//   CSV   a header row naming the columns scene, work (and optionally name, quality, scene_scale),
//         every other column a setting "stage.key"; an empty cell leaves the default.
// Relative paths are relative to the manifest's folder. "work" may be left out: then
// <manifest folder>/work/<name>.
#include <filesystem>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/pipeline/stages.hpp"

namespace nf::batch {

struct BatchTask {
  std::string name;                    // unique; the scene folder's name unless given
  std::filesystem::path scene, work;   // absolute
  std::string quality = "default";
  double scene_scale = 0;              // cm per scene unit; 0: from the scene file or the eyes
  std::vector<std::string> settings;   // "stage.key=value", defaults first, then the scene's own
  std::string origin;                  // where the manifest gives it ("scenes[2]", "line 4"), for messages
};

// Reads and checks a manifest (InputError naming the file, the row or entry and the field).
// Every task's settings are checked against the stages' schemas (an unknown key, a bad value).
std::vector<BatchTask> read_manifest(const std::filesystem::path& file);

// The `reconstruct` run a task is: checked when the manifest is read, run by `batch task`.
pipeline::ReconstructOptions reconstruct_options(const BatchTask& task);

json to_json(const BatchTask& task);
BatchTask task_from_json(const json& j);

}  // namespace nf::batch
