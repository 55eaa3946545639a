#pragma once
// The surface stage (`neus`): visual hull, normalisation, NeuS training with checkpoints, the
// outer mesh M_NeuS and previews. Its files are NeusOutputs below; its settings are declared in
// neus_settings() (`nf_gpu reconstruct --help-stage neus` prints them).
#include "engine/neus/neus_quality.hpp"
#include "engine/pipeline/stage.hpp"

namespace nf::pipeline {

// What the stage writes into WORK/neus/. Later stages read these paths, never retype them.
struct NeusOutputs {
  std::filesystem::path dir;
  std::filesystem::path outer() const { return dir / "outer.ply"; }               // M_NeuS, scene units
  std::filesystem::path model() const { return dir / "model.nfwt"; }              // field + config + normalisation
  std::filesystem::path normalisation() const { return dir / "normalisation.json"; }
  std::filesystem::path training() const { return dir / "training.jsonl"; }      // the loss curve
  std::filesystem::path metrics() const { return dir / "metrics.json"; }          // the stage summary
  std::filesystem::path renders() const { return dir / "renders"; }               // held-out views: rgb, normal, depth
};
inline NeusOutputs neus_outputs(const std::filesystem::path& work) { return {work / "neus"}; }

const SettingsSchema<neus::NeusQuality>& neus_settings();
// Every camera's name, size, intrinsics and pose, as the stages that read the photos key them.
json cameras_json(const io::Scene& scene);

class NeusStage : public SettingsStage<neus::NeusQuality> {
 public:
  NeusStage() : SettingsStage(neus_settings()) {}
  std::vector<std::string> memory_settings() const override { return {"rays", "samples_per_ray", "mesh_resolution", "hull_resolution"}; }
  std::vector<std::filesystem::path> inputs(const StageContext& context) const override;
  json parameters(const StageContext& context) const override;
  json run(StageContext& context, const std::filesystem::path& out, const std::filesystem::path& resume) override;
};

}  // namespace nf::pipeline
