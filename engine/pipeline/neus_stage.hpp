#pragma once
// The surface stage (`neus`): visual hull, normalisation, NeuS training with checkpoints, the
// outer mesh M_NeuS and previews. Writes WORK/neus/: outer.ply (scene units), model.nfwt (the
// field, with its configuration and the normalisation), normalisation.json, training.jsonl (the
// loss curve), metrics.json, renders/ (held-out views: rgb, normal, depth PNG and depth EXR).
// Settings (context.settings["neus"], `--set neus.KEY=VALUE`): steps, rays, samples_per_ray, seed, lr,
// variance_lr, hull_fit_steps, mesh_resolution, hull_resolution.
#include "engine/pipeline/stage.hpp"

namespace nf::pipeline {

class NeusStage : public Stage {
 public:
  std::string name() const override { return "neus"; }
  std::vector<std::filesystem::path> inputs(const StageContext& context) const override;
  json parameters(const StageContext& context) const override;
  json run(StageContext& context, const std::filesystem::path& out, const std::filesystem::path& resume) override;
};

}  // namespace nf::pipeline
