#include "engine/pipeline/stages.hpp"

#include <algorithm>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/output_guard.hpp"
#include "engine/core/text.hpp"
#include "engine/pipeline/body_stage.hpp"
#include "engine/pipeline/defur_stage.hpp"
#include "engine/pipeline/export_stage.hpp"
#include "engine/pipeline/frames_stage.hpp"
#include "engine/pipeline/fur_stage.hpp"
#include "engine/pipeline/knowledge_stage.hpp"
#include "engine/pipeline/neus_stage.hpp"
#include "engine/pipeline/work_lock.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;

// Fewer views than this and the surface cannot be whole: say so before minutes of work.
constexpr std::size_t kFewViews = 8;

std::vector<std::unique_ptr<Stage>> reconstruction_stages() {
  std::vector<std::unique_ptr<Stage>> stages;
  stages.push_back(std::make_unique<NeusStage>());
  stages.push_back(std::make_unique<BodyStage>());
  stages.push_back(std::make_unique<KnowledgeStage>());
  stages.push_back(std::make_unique<DefurStage>());
  stages.push_back(std::make_unique<FramesStage>());
  stages.push_back(std::make_unique<FurStage>());
  stages.push_back(std::make_unique<ExportStage>());
  return stages;
}

void apply_setting(json& settings, const std::string& assignment) {
  const std::size_t dot = assignment.find('.'), eq = assignment.find('=');
  if (dot == std::string::npos || eq == std::string::npos || dot == 0 || eq < dot + 2)
    throw UsageError("--set '" + assignment + "': expected stage.key=value, e.g. neus.steps=300");
  const std::string stage = assignment.substr(0, dot), key = assignment.substr(dot + 1, eq - dot - 1);
  // Kept as typed: the stage's schema reads it as its setting's type, so a path like "1.50" or
  // "null" stays the text the user wrote.
  settings[stage][key] = assignment.substr(eq + 1);
}

json check_reconstruct_options(const std::vector<std::unique_ptr<Stage>>& stages, const ReconstructOptions& options) {
  const auto& qualities = quality_names();
  if (std::find(qualities.begin(), qualities.end(), options.quality) == qualities.end())
    throw UsageError("--quality must be one of " + join(qualities) + ", got '" + options.quality + "'" +
                     did_you_mean(options.quality, qualities));
  std::vector<std::string> names;
  for (const auto& s : stages) names.push_back(s->name());
  for (const auto& [option, stage] : {std::pair{"--from", options.run.from}, std::pair{"--to", options.run.to}})
    if (!stage.empty() && std::find(names.begin(), names.end(), stage) == names.end())
      throw UsageError(std::string(option) + ": no stage named '" + stage + "'" + did_you_mean(stage, names) +
                       " (stages: " + join(names) + ")");
  json settings = json::object();
  for (const std::string& s : options.settings) apply_setting(settings, s);
  if (options.scene_scale > 0) {
    if (settings.contains("knowledge") && settings["knowledge"].contains("cm_per_unit"))
      throw UsageError("--scene-scale and --set knowledge.cm_per_unit both give the scene's scale: give one");
    settings["knowledge"]["cm_per_unit"] = options.scene_scale;
  }
  for (const auto& [stage, values] : settings.items()) {
    const auto it = std::find(names.begin(), names.end(), stage);
    if (it == names.end())
      throw UsageError("--set " + stage + ".*: no stage named '" + stage + "'" + did_you_mean(stage, names) +
                       " (stages: " + join(names) + ")");
  }
  for (const auto& s : stages) s->settings().values(options.quality, settings.value(s->name(), json::object()));

  if (!fs::exists(options.scene)) throw InputError("--scene " + options.scene.string() + ": no such file or folder");
  require_folder_or_absent(options.work, "--out");
  const fs::path scene_abs = fs::absolute(options.scene);
  refuse_output_inside(options.work, fs::is_directory(scene_abs) ? scene_abs : scene_abs.parent_path(), "--out", "scene");
  const std::vector<std::string> needed = stages_needed(stages, options.run.to);
  for (const auto& s : stages)
    if (std::find(needed.begin(), needed.end(), s->name()) != needed.end())
      s->check_needed_settings(options.quality, settings.value(s->name(), json::object()));
  return settings;
}

json check_reconstruct_options(const ReconstructOptions& options) {
  return check_reconstruct_options(reconstruction_stages(), options);
}

std::vector<StageOutcome> reconstruct(gpu::Context& context, const ReconstructOptions& options) {
  const auto stages = reconstruction_stages();
  json settings = check_reconstruct_options(stages, options);
  const WorkLock lock(options.work, "nf_gpu reconstruct --scene " + options.scene.string());
  const fs::path scene_abs = fs::absolute(options.scene);
  const fs::path scene_dir = fs::is_directory(scene_abs) ? scene_abs : scene_abs.parent_path();
  StageContext c{context, scene_dir, io::read_scene(options.scene), options.work, options.quality, std::move(settings)};
  c.scene.check_files(options.scene.string());
  if (c.scene.cameras.size() < kFewViews)
    log::warn("the scene has only ", c.scene.cameras.size(), " views: the surface, and every stage after it, will be poor; NeuS needs the "
              "animal seen from all sides (20 views or more around it)");
  return run_pipeline(stages, c, options.run);
}

std::vector<std::string> stage_names() {
  std::vector<std::string> names;
  for (const auto& s : reconstruction_stages()) names.push_back(s->name());
  return names;
}

std::string describe_stage_settings(const std::string& stage, bool markdown) {
  for (const auto& s : reconstruction_stages())
    if (s->name() == stage) return describe_settings(s->settings(), markdown);
  const std::vector<std::string> names = stage_names();
  throw UsageError("--help-stage: no stage named '" + stage + "'" + did_you_mean(stage, names) + " (stages: " +
                   join(names) + ")");
}

}  // namespace nf::pipeline
