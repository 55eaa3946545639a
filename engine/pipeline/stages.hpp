#pragma once
// The stages of `nf_gpu reconstruct`, in order (README, Stages of reconstruct), and the command itself. A new stage
// is one more line in stages.cpp; the framework (pipeline.hpp) needs no change.
#include <memory>
#include <string>
#include <vector>

#include "engine/pipeline/pipeline.hpp"
#include "engine/pipeline/stage.hpp"

namespace nf::pipeline {

std::vector<std::unique_ptr<Stage>> reconstruction_stages();

struct ReconstructOptions {
  std::filesystem::path scene, work;
  std::string quality = "default";
  RunOptions run;
  std::vector<std::string> settings;  // "stage.key=value", e.g. "neus.steps=300"
  double scene_scale = 0;              // --scene-scale: cm per scene unit (the knowledge stage's cm_per_unit); 0: none given
};

// Checks everything a run can check before it starts, and touches no file: the quality, --from
// and --to, every --set (unknown stage or key with a "did you mean", type, range, the stages'
// own cross-checks), --out (not a file, not inside the scene folder). Returns the settings as
// {"stage": {"key": value}}. UsageError (exit 2) or InputError (exit 1) name what is wrong.
json check_reconstruct_options(const std::vector<std::unique_ptr<Stage>>& stages, const ReconstructOptions& options);
// The same against reconstruct's own stages (what `nf_gpu batch` checks each scene with).
json check_reconstruct_options(const ReconstructOptions& options);

// check_reconstruct_options, then reads the scene (any format io::read_scene takes) and checks its
// files (sizes, truncation) before any stage runs, then runs the stages.
std::vector<StageOutcome> reconstruct(gpu::Context& context, const ReconstructOptions& options);

// Adds one "stage.key=value" override, the value kept as the text typed (the schema converts it).
void apply_setting(json& settings, const std::string& assignment);

// For `--help-stage`: the stage's settings table (markdown for the README), or UsageError naming
// the stages when there is no such stage.
std::string describe_stage_settings(const std::string& stage, bool markdown);
// "neus, body, ..." in order, for help texts.
std::vector<std::string> stage_names();

}  // namespace nf::pipeline
