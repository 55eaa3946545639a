#pragma once
// The knowledge stage (`knowledge`): per-region fur length, effective thickness and growth
// direction, and the eye distance, from one source a run names (`--set knowledge.file=`,
// `knowledge.preset=` or `knowledge.vlm=` + `knowledge.model=`); the directions also in world
// coordinates through the body stage's animal frame; and the metric scale (cm per scene unit).
// Its files are KnowledgeOutputs below; `nf_gpu reconstruct --help-stage knowledge` lists its settings.
#include <array>
#include <string>

#include <glm/glm.hpp>

#include "engine/knowledge/knowledge.hpp"
#include "engine/pipeline/stage.hpp"

namespace nf::pipeline {

struct KnowledgeOutputs {
  std::filesystem::path dir;
  std::filesystem::path knowledge() const { return dir / "knowledge.json"; }     // animal frame; editable, feeds knowledge.file
  std::filesystem::path directions_world() const { return dir / "directions_world.json"; }  // {region: [x, y, z]} world
  std::filesystem::path scale() const { return dir / "scale.json"; }             // cm per scene unit and its source
  std::filesystem::path transcript() const { return dir / "transcript.jsonl"; }  // VLM: every request and answer
  std::filesystem::path images() const { return dir / "images"; }                // VLM: the photos sent
  std::filesystem::path consensus() const { return dir / "consensus.json"; }     // VLM, samples > 1: the spread
  std::filesystem::path metrics() const { return dir / "metrics.json"; }         // the stage summary
};
inline KnowledgeOutputs knowledge_outputs(const std::filesystem::path& work) { return {work / "knowledge"}; }

struct KnowledgeSettings {
  std::string file, preset, vlm, model;
  std::string animal = "animal";  // the name written for a VLM annotation
  int samples = 1;
  int image_size = 768;
  double timeout_s = 180, retry_wait_s = 2, max_answer_mb = 8, temperature = -1;
  int retries = 4;
  double cm_per_unit = 0;  // > 0: the scene's scale, given (--scene-scale)
};
const SettingsSchema<KnowledgeSettings>& knowledge_settings();

// The environment variable the API key is read from.
inline constexpr const char* kVlmKeyVariable = "NF_VLM_API_KEY";

// The scale a finished knowledge stage wrote (cm per scene unit).
double read_metric_scale(const KnowledgeOutputs& outputs);
// The regions' growth directions in world coordinates it wrote (unit; zero for a region it lacks).
std::array<glm::vec3, body::kRegionCount> read_directions_world(const KnowledgeOutputs& outputs);

class KnowledgeStage : public SettingsStage<KnowledgeSettings> {
 public:
  KnowledgeStage() : SettingsStage(knowledge_settings()) {}
  std::vector<std::string> memory_settings() const override { return {"image_size"}; }
  std::vector<std::string> depends_on() const override { return {"body"}; }
  // No source named: stop before the first stage runs, not after an hour of neus.
  void check_needed_settings(const std::string& quality, const json& overrides) const override;
  std::vector<std::filesystem::path> inputs(const StageContext& context) const override;
  json parameters(const StageContext& context) const override;
  json run(StageContext& context, const std::filesystem::path& out, const std::filesystem::path& resume) override;
};

}  // namespace nf::pipeline
