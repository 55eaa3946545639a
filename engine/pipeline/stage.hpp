#pragma once
// A stage of `nf_gpu reconstruct`: it names the files it reads and the parameters that
// change its result, and writes its outputs into a folder the framework gives it. Everything else
// (hashing, skipping, atomic replacement, resume folders, records) is the framework's
// (pipeline.hpp), so adding a stage is writing one of these (a SettingsStage, below) and listing it
// in stages.cpp.
#include <filesystem>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/io/scene.hpp"
#include "engine/pipeline/settings.hpp"

namespace nf::gpu {
class Context;
}

namespace nf::pipeline {

struct StageContext {
  gpu::Context& gpu;
  std::filesystem::path scene_dir;  // the input scene (never written)
  io::Scene scene;                  // read once
  std::filesystem::path work;       // WORK: one folder per stage
  std::string quality;              // draft | default | paper
  json settings = json::object();   // per-stage overrides of the preset: {"neus": {"steps": 500}}
};

class Stage {
 public:
  virtual ~Stage() = default;
  virtual std::string name() const = 0;
  // Stages whose outputs this one reads: they run (or are found unchanged) first, and a rerun of
  // one of them reruns this one.
  virtual std::vector<std::string> depends_on() const { return {}; }
  // The stage's `--set` settings; validated for every stage before any stage runs.
  virtual const StageSettings& settings() const = 0;
  // Checked before any stage runs, for a stage that this run needs: what only matters when it
  // runs (a choice it cannot do without). Throws UsageError.
  virtual void check_needed_settings(const std::string& quality, const json& overrides) const {
    (void)quality, (void)overrides;
  }
  // The settings that set how much device and host memory the stage needs, the most effective
  // first: an out-of-memory error in the stage names them with their values.
  virtual std::vector<std::string> memory_settings() const { return {}; }
  // Files read (scene files, or earlier stages' outputs under WORK); their content is hashed.
  // A missing file under WORK/<stage>/ is reported as "run stage <stage>".
  virtual std::vector<std::filesystem::path> inputs(const StageContext& context) const = 0;
  // Everything else that changes the result (settings, camera parameters, a version).
  virtual json parameters(const StageContext& context) const = 0;
  // Writes the outputs into `out` (a fresh folder that becomes WORK/<name> when this returns).
  // `resume` survives a killed run (checkpoints) and is emptied once the stage has finished.
  // A stage with checkpoints polls nf::interrupted() (Ctrl-C), saves one and throws Interrupted.
  // Returns a summary for the stage record: what it cost and what it achieved.
  virtual json run(StageContext& context, const std::filesystem::path& out, const std::filesystem::path& resume) = 0;
};

// The run's values of one stage's settings: the quality's preset with the run's `--set` overrides.
// The one way any stage resolves settings, its own or (for a key it shares) another stage's.
template <class S>
S resolve_settings(const SettingsSchema<S>& schema, const StageContext& context) {
  return schema.resolve(context.quality, context.settings.value(schema.stage(), json::object()));
}
// The same values as JSON, as stage keys and records keep them.
inline json settings_values(const StageSettings& schema, const StageContext& context) {
  return schema.values(context.quality, context.settings.value(schema.stage(), json::object()));
}

// A stage whose settings are one typed schema: its name is the schema's, settings() is the schema,
// settings_of() the run's values, and key_of() the start of every stage's parameters() (its
// version and resolved settings), so a stage writes none of these itself.
template <class S>
class SettingsStage : public Stage {
 public:
  explicit SettingsStage(const SettingsSchema<S>& schema) : schema_(schema) {}
  std::string name() const final { return schema_.stage(); }
  const StageSettings& settings() const final { return schema_; }
  S settings_of(const StageContext& context) const { return resolve_settings(schema_, context); }
  json key_of(const StageContext& context, int stage_version) const {
    return {{"stage_version", stage_version}, {"settings", settings_values(schema_, context)}};
  }

 private:
  const SettingsSchema<S>& schema_;
};

}  // namespace nf::pipeline
