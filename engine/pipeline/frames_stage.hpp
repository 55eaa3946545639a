#pragma once
// The frames stage (`frames`): a smooth tangent direction field on M_bald's faces aligned with the
// knowledge's growth directions (geometry/tangent_field.hpp), each face's frame (tangent,
// bitangent = normal x tangent, normal), and the fur roots (fur/roots.hpp). Its files are
// FramesOutputs below; `nf_gpu reconstruct --help-stage frames` lists its settings.
#include "engine/pipeline/stage.hpp"

namespace nf::pipeline {

struct FramesOutputs {
  std::filesystem::path dir;
  std::filesystem::path frames() const { return dir / "frames.npz"; }  // tangent, bitangent, normal per face of defur/bald.ply
  std::filesystem::path roots() const { return dir / "roots.npz"; }    // the roots (fur/roots.hpp)
  std::filesystem::path metrics() const { return dir / "metrics.json"; }
};
inline FramesOutputs frames_outputs(const std::filesystem::path& work) { return {work / "frames"}; }

struct FramesSettings {
  double smoothing_cm = 1.0;
  bool guide = true;
  int roots = 500000;
  unsigned seed = 1;
};
const SettingsSchema<FramesSettings>& frames_settings();

class FramesStage : public SettingsStage<FramesSettings> {
 public:
  FramesStage() : SettingsStage(frames_settings()) {}
  std::vector<std::string> memory_settings() const override { return {"roots"}; }
  std::vector<std::string> depends_on() const override { return {"defur"}; }
  std::vector<std::filesystem::path> inputs(const StageContext& context) const override;
  json parameters(const StageContext& context) const override;
  json run(StageContext& context, const std::filesystem::path& out, const std::filesystem::path& resume) override;
};

}  // namespace nf::pipeline
