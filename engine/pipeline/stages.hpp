#pragma once
// The stages of `nf_gpu reconstruct`, in order (DESIGN §1), and the command itself. A new stage
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
};

// Reads the scene (any format io::read_scene takes), refuses a WORK inside the scene folder (the
// input is never written), and runs the stages. InputError/UsageError name the bad argument.
std::vector<StageOutcome> reconstruct(gpu::Context& context, const ReconstructOptions& options);

// Adds one "stage.key=value" override (value parsed as JSON, else kept as a string).
void apply_setting(json& settings, const std::string& assignment);

}  // namespace nf::pipeline
