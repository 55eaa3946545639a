#pragma once
// The body stage (`body`): the rigged quadruped fitted to M_NeuS in three stages (engine/body/
// body_fit.hpp), its regions moved onto M_NeuS by nearest vertex, the eye centres and the animal
// frame. Its files are BodyOutputs below; its settings are declared in body_settings()
// (`nf_gpu reconstruct --help-stage body`).
#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "engine/body/body_fit.hpp"
#include "engine/pipeline/stage.hpp"

namespace nf::pipeline {

struct BodyOutputs {
  std::filesystem::path dir;
  std::filesystem::path outer_regions() const { return dir / "outer_regions.ply"; }  // M_NeuS + `region` per vertex
  std::filesystem::path fitted() const { return dir / "fitted.ply"; }                // the fitted body, world units
  std::filesystem::path params() const { return dir / "params.json"; }               // shape, pose, placement, losses
  std::filesystem::path eyes() const { return dir / "eyes.json"; }                   // eye centres, world
  std::filesystem::path animal_frame() const { return dir / "animal_frame.json"; }   // animal frame -> world
  std::filesystem::path fit_state() const { return dir / "fit.json"; }               // the fit's variables, for the re-fit
  std::filesystem::path metrics() const { return dir / "metrics.json"; }             // the stage summary
  std::filesystem::path previews() const { return dir / "previews"; }               // region colours, 2 cameras
};
inline BodyOutputs body_outputs(const std::filesystem::path& work) { return {work / "body"}; }
// What later stages read of a finished body stage: the animal frame -> world map (its columns:
// left, up, forward, scaled alike, and the origin) and the eye centres' distance in scene units.
// InputError naming the file and field when one is malformed.
glm::dmat4 read_animal_to_world(const BodyOutputs& outputs);
double read_eye_distance(const BodyOutputs& outputs);
// Whether eyes.json's eyes were found in the photos (else they are the fitted template's).
bool read_eyes_from_photos(const BodyOutputs& outputs);
// The fitted head-and-body length in scene units; none when the model's joints do not give it.
std::optional<double> read_head_and_body_length(const BodyOutputs& outputs);
// The fit's variables and frame (what body::refit_body starts from; the posed meshes are not
// rebuilt). InputError naming the file and field when it is malformed or does not match `model`.
body::BodyFit read_body_fit(const BodyOutputs& outputs, const body::BodyModel& model);

struct BodySettings {
  body::BodyFitOptions fit;
  std::string model;  // "" (the built-in quadruped family) or a SMAL-layout .npz
  int preview_views = 2;
  int photo_eyes = 0;  // find the eyes in the photos (else the fit's); off: on synth scenes worse than the fit (docs/method.md)
};
const SettingsSchema<BodySettings>& body_settings();
// The body model a run's settings name (the built-in family or a SMAL file).
body::BodyModel body_model_of(const BodySettings& settings);

class BodyStage : public SettingsStage<BodySettings> {
 public:
  BodyStage() : SettingsStage(body_settings()) {}
  std::vector<std::string> memory_settings() const override { return {"samples"}; }
  std::vector<std::string> depends_on() const override { return {"neus"}; }
  std::vector<std::filesystem::path> inputs(const StageContext& context) const override;
  json parameters(const StageContext& context) const override;
  json run(StageContext& context, const std::filesystem::path& out, const std::filesystem::path& resume) override;
};

}  // namespace nf::pipeline
