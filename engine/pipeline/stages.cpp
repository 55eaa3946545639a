#include "engine/pipeline/stages.hpp"

#include "engine/core/error.hpp"
#include "engine/pipeline/neus_stage.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;

std::vector<std::unique_ptr<Stage>> reconstruction_stages() {
  std::vector<std::unique_ptr<Stage>> stages;
  stages.push_back(std::make_unique<NeusStage>());
  // Next, as they land: body, knowledge, defur, frames, fur, export.
  return stages;
}

void apply_setting(json& settings, const std::string& assignment) {
  const std::size_t dot = assignment.find('.'), eq = assignment.find('=');
  if (dot == std::string::npos || eq == std::string::npos || dot == 0 || eq < dot + 2)
    throw UsageError("--set '" + assignment + "': expected stage.key=value, e.g. neus.steps=300");
  const std::string stage = assignment.substr(0, dot), key = assignment.substr(dot + 1, eq - dot - 1);
  const std::string text = assignment.substr(eq + 1);
  json value = json::parse(text, nullptr, false);
  if (value.is_discarded()) value = text;
  settings[stage][key] = value;
}

std::vector<StageOutcome> reconstruct(gpu::Context& context, const ReconstructOptions& options) {
  if (options.quality != "draft" && options.quality != "default" && options.quality != "paper")
    throw UsageError("--quality must be draft, default or paper, got '" + options.quality + "'");
  if (!fs::exists(options.scene)) throw InputError(options.scene.string() + ": no such scene");
  const fs::path scene_abs = fs::absolute(options.scene);
  const fs::path scene_dir = fs::is_directory(scene_abs) ? scene_abs : scene_abs.parent_path();
  const fs::path work = fs::weakly_canonical(options.work), root = fs::weakly_canonical(scene_dir);
  const fs::path rel = work.lexically_relative(root);
  if (!rel.empty() && *rel.begin() != "..")
    throw UsageError("--out " + options.work.string() + " lies inside the scene folder " + scene_dir.string() +
                     "; the input is never written, choose a folder outside it");
  StageContext c{context, scene_dir, io::read_scene(options.scene), options.work, options.quality};
  c.scene.check_files(options.scene.string());
  for (const std::string& s : options.settings) apply_setting(c.settings, s);
  const auto stages = reconstruction_stages();
  for (const auto& [stage, values] : c.settings.items()) {
    bool known = false;
    for (const auto& s : stages) known |= s->name() == stage;
    if (!known) throw UsageError("--set: no stage named '" + stage + "'");
  }
  return run_pipeline(stages, c, options.run);
}

}  // namespace nf::pipeline
