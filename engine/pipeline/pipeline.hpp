#pragma once
// The stage framework of `nf_gpu reconstruct`. For each stage in order:
//   key = its parameters + the content hashes of its inputs;
//   skip when WORK/<name>/stage.json holds the same key (and no --from forces it);
//   else run into WORK/<name>.partial, write stage.json there, and swap it in for WORK/<name>
//   (the old folder is removed only after the new one is complete);
//   checkpoints live in WORK/.resume/<name>, kept across kills, tied to the key, removed on success.
// A folder WORK/<name> without our stage.json is somebody else's: the run stops rather than touch it.
#include <memory>
#include <string>
#include <vector>

#include "engine/pipeline/stage.hpp"

namespace nf::pipeline {

struct RunOptions {
  std::string from;  // rerun this stage and every later one even when unchanged ("" = none)
  std::string to;    // stop after this stage ("" = run to the end)
};

struct StageOutcome {
  std::string name;
  bool ran = false;   // false: skipped, its record matched
  double seconds = 0;
  json summary;
};

// Throws UsageError for an unknown --from/--to, InputError for a foreign WORK/<name> folder.
std::vector<StageOutcome> run_pipeline(const std::vector<std::unique_ptr<Stage>>& stages, StageContext& context,
                                       const RunOptions& options);

// The record file of a finished stage.
std::filesystem::path stage_record(const std::filesystem::path& work, const std::string& stage);

}  // namespace nf::pipeline
