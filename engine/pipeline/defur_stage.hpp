#pragma once
// The defur stage (`defur`): the bald body M_bald from M_NeuS and the knowledge's thickness
// (engine/defur/defur_surface.hpp), the body re-fitted to M_bald for its regions, the knowledge per
// vertex of M_bald, the bald body's SDF grid for the penetration loss, and the non-bald masks per
// camera. Its files are DefurOutputs below; `nf_gpu reconstruct --help-stage defur` lists its settings.
#include "engine/pipeline/stage.hpp"

namespace nf::pipeline {

struct DefurOutputs {
  std::filesystem::path dir;
  std::filesystem::path bald() const { return dir / "bald.ply"; }              // M_bald, normals and `region` per vertex
  std::filesystem::path vertex_fur() const { return dir / "vertex_fur.npz"; }  // region, length (scene units), direction (world) per vertex
  std::filesystem::path bald_sdf() const { return dir / "bald_sdf.npz"; }      // signed distance to M_bald on a grid
  std::filesystem::path refit() const { return dir / "refit.ply"; }            // the body re-fitted to M_bald
  std::filesystem::path masks() const { return dir / "nonbald_masks"; }        // per camera: 1 where fur grows
  std::filesystem::path previews() const { return dir / "previews"; }          // M_bald in region colours over M_NeuS
  std::filesystem::path metrics() const { return dir / "metrics.json"; }       // the stage summary
};
inline DefurOutputs defur_outputs(const std::filesystem::path& work) { return {work / "defur"}; }

struct DefurSettings {
  int resolution = 256;
  int faces = 160000;
  int thickness_smoothing = 100;
  int knowledge_smoothing = 20;
  int max_hole_edges = 100;
  int sdf_resolution = 0;
  bool refit = true;
  bool masks = true;
  int preview_views = 2;
};
const SettingsSchema<DefurSettings>& defur_settings();

class DefurStage : public SettingsStage<DefurSettings> {
 public:
  DefurStage() : SettingsStage(defur_settings()) {}
  std::vector<std::string> memory_settings() const override { return {"resolution", "sdf_resolution", "faces"}; }
  std::vector<std::string> depends_on() const override { return {"body", "knowledge"}; }
  std::vector<std::filesystem::path> inputs(const StageContext& context) const override;
  json parameters(const StageContext& context) const override;
  json run(StageContext& context, const std::filesystem::path& out, const std::filesystem::path& resume) override;
};

}  // namespace nf::pipeline
