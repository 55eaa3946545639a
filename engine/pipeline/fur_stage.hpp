#pragma once
// The fur stage (`fur`): the neural fur field optimised through strand splatting with the paper's
// six losses (fur/fur_trainer.hpp), then inference of any number of strands streamed to
// strands.hair. Its files are FurOutputs below; `nf_gpu reconstruct --help-stage fur` lists its
// settings.
#include "engine/fur/fur_trainer.hpp"
#include "engine/pipeline/stage.hpp"

namespace nf::pipeline {

struct FurOutputs {
  std::filesystem::path dir;
  std::filesystem::path strands() const { return dir / "strands.hair"; }    // the groom, scene units, 100 points per strand
  std::filesystem::path regions() const { return dir / "regions.npz"; }     // `region` (i4) per strand of strands.hair
  std::filesystem::path scale() const { return dir / "scale.json"; }        // cm per scene unit (nf_gpu metrics reads it)
  std::filesystem::path model() const { return dir / "model.nfwt"; }        // the fur field's weights, box and configuration
  std::filesystem::path training() const { return dir / "training.jsonl"; } // the loss curve: every 10th step
  std::filesystem::path metrics() const { return dir / "metrics.json"; }    // the stage summary
  std::filesystem::path previews() const { return dir / "previews"; }       // the groom over held-out photos
  std::filesystem::path roots() const { return dir / "roots.npz"; }         // when the groom's roots are not frames/roots.npz
  std::filesystem::path curve() const { return dir / "curve.jsonl"; }       // with curve_seconds: scores against training time
  std::filesystem::path colors() const { return dir / "colors.npz"; }       // `rgb` (strands x controls x 3, linear) and `seen` per strand
  std::filesystem::path body_colors() const { return dir / "body_colors.npz"; }  // the same per vertex of M_bald (one control)
};
inline FurOutputs fur_outputs(const std::filesystem::path& work) { return {work / "fur"}; }
// The roots file of the groom in fur/strands.hair (one root per strand, same order): fur/roots.npz
// or frames/roots.npz, as fur/metrics.json records. InputError when the record is missing.
std::filesystem::path groom_roots_file(const std::filesystem::path& work);
// frames.npz's per-face frames of M_bald (`faces` faces); InputError naming the file.
fur::FaceFrames read_face_frames(const std::filesystem::path& file, std::size_t faces);

struct FurSettings {
  fur::FurTrainingOptions training;
  fur::FurFieldConfig field;
  std::uint32_t resolution = 512;   // longer side of the rendered views (0: the photos')
  // Native-resolution patches (fur_patches.hpp): the side of the window of a photo each image step
  // renders at the photo's own resolution (0: the whole view at `resolution`), and how many fixed
  // patches of each held-out view score the groom. Off by default: on the scenes measured (a cat
  // at 1024 px, a cat of other shading, hair width and noise at 512 px) they trained 2-3.6x slower
  // and no better at 2 cm or 2 mm (docs/fur-stage.md, "Native-resolution patches").
  std::uint32_t patch = 0;
  std::uint32_t held_out_patches = 4;
  // With patches: at most this many Gabor maps, the photo's and its halvings' (orientation_scales.hpp),
  // as many as the fur's length in the photo calls for (fur_resolution.hpp, gabor_scales_for).
  std::uint32_t gabor_scales = 3;
  std::uint32_t margin_px = 8;
  int hold_out_every = 5;
  std::uint32_t strands = 500000;   // inferred
  std::uint32_t metric_points = 25;     // per strand, resampled along its arc length
  std::uint32_t metric_strands = 20000;  // the paper compares 100,000 (preset paper); the mm thresholds cost ~N^2
  std::uint32_t score_strands = 0;  // strands rendered to score held-out views (0: the training batch)
  int preview_views = 3;
  // Colours along each strand from the photos (fur/strand_colors.hpp): how many (0: no colours).
  std::uint32_t color_controls = 3;
  double color_hidden_depth = 0.35;  // a control deeper than this share of its strand's length behind M_NeuS is not seen
  // Seconds of training between two points of curve.jsonl (0: none): the groom scored against the
  // held-out views and, on synth scenes, the true strands, while it trains (the bench's curves).
  double curve_seconds = 0;
  // Inputs swapped for the scene's ground truth (synth scenes), to measure what the earlier stages'
  // errors cost: "knowledge" (the true lengths and directions on the pipeline's M_bald), "all" (the
  // true bald body, knowledge and roots; its baseline groom is the baseline (b)).
  std::string truth = "none";
  // The orientation target: "gabor" (the photos' Gabor maps) or, on synth scenes written with
  // --true-orientation, "truth" (gt/orientation/: what a perfect orientation map would buy).
  std::string orientation_target = "gabor";
  // Which groom is kept (fur_selection.hpp): "auto" the 0-step, warm-up or trained groom, a later
  // one only where the held-out views and M_NeuS say it helped (and training stops after the
  // warm-up where no photo resolves the fur); "trained" always; "warm" the warm-up's.
  std::string select = "auto";
};
FurSettings fur_quality_preset(const std::string& quality);
const SettingsSchema<FurSettings>& fur_settings();

class FurStage : public SettingsStage<FurSettings> {
 public:
  FurStage() : SettingsStage(fur_settings()) {}
  std::vector<std::string> memory_settings() const override { return {"batch", "resolution", "patch", "chamfer_queries", "strands", "metric_strands"}; }
  std::vector<std::string> depends_on() const override { return {"frames"}; }
  std::vector<std::filesystem::path> inputs(const StageContext& context) const override;
  json parameters(const StageContext& context) const override;
  json run(StageContext& context, const std::filesystem::path& out, const std::filesystem::path& resume) override;
};

}  // namespace nf::pipeline
