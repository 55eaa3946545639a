#pragma once
// The stage framework of `nf_gpu reconstruct`. Stages are listed after the stages they depend on
// (Stage::depends_on); for each stage needed (all, or --to and what it depends on), in order:
//   key = its parameters + the content hashes of its inputs;
//   a missing input under WORK/<other>/ is an InputError that says to run <other>;
//   skip when WORK/<name>/stage.json holds the same key, unless --from names it or a stage it
//   depends on (directly or not), or a stage it depends on ran in this run;
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
  std::string from;  // rerun this stage and every stage that depends on it, even when unchanged ("" = none)
  std::string to;    // run only this stage and the stages it depends on ("" = all)
  bool quality_named = false;  // --quality was given: a stage made at another quality is not kept
};

struct StageOutcome {
  std::string name;
  bool ran = false;   // false: skipped, its record matched (or kept, below)
  double seconds = 0;
  json summary;
  // Not empty when the cached result was kept although this run's settings for the stage differ:
  // which settings, and how to remake it. Only for a stage upstream of --to whose inputs are
  // unchanged and whose settings the user did not name.
  std::string kept;
};

// Throws UsageError for an unknown --from/--to (or a --from that --to does not depend on),
// InputError for a foreign WORK/<name> folder or a missing input. A stage that throws leaves no
// WORK/<name>.partial behind; its checkpoint stays for the next run.
std::vector<StageOutcome> run_pipeline(const std::vector<std::unique_ptr<Stage>>& stages, StageContext& context,
                                       const RunOptions& options);

// The stages a run with `--to to` needs: `to` and what it depends on, or all when `to` is empty.
std::vector<std::string> stages_needed(const std::vector<std::unique_ptr<Stage>>& stages, const std::string& to);

// The record file of a finished stage.
std::filesystem::path stage_record(const std::filesystem::path& work, const std::string& stage);

}  // namespace nf::pipeline
