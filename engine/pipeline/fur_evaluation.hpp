#pragma once
// What the fur stage measures besides training, for people and for the bench: the groom scored on
// the held-out views (with the baseline groom and, on synth scenes, the true groom rendered alike),
// the ground truth of synth scenes, the score curve against training time (fur.curve_seconds), and
// the earlier stages' results swapped for the truth (fur.truth) to measure what their errors cost.
// The stage's own decisions (which groom to keep) use only the held-out views and M_NeuS.
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/defur/vertex_fur.hpp"
#include "engine/fur/fur_trainer.hpp"
#include "engine/fur/ground_truth_inputs.hpp"
#include "engine/geometry/mesh.hpp"
#include "engine/io/scene.hpp"
#include "engine/metrics/color_scores.hpp"
#include "engine/metrics/groom_scores.hpp"

namespace nf::pipeline {

struct FurSettings;

// A groom rendered into each held-out view and scored against its targets (means over the views).
struct HeldOutScores {
  json views = json::array();
  double silhouette_iou = 0, orientation_error_deg = 0;
};
json held_out_json(const HeldOutScores& h);
// The field's strands at `strands` seeded roots; `images` (when given) keeps the renderings;
// `before_each` may stop the work (it throws).
HeldOutScores score_field_held_out(fur::FurTrainer& trainer, const std::vector<fur::FurView>& views, const io::Scene& scene,
                                   std::uint32_t strands, unsigned seed, std::vector<std::vector<float>>* images,
                                   const std::function<void()>& before_each = {});
// Given strands (strands x 100 x 3) rendered like the field's: the baseline groom, or the true one.
HeldOutScores score_strands_held_out(fur::FurTrainer& trainer, const std::vector<fur::FurView>& views, const io::Scene& scene,
                                     const std::vector<float>& points, const std::function<void()>& before_each);

// The field's strands at a fixed subset of `count` roots (seeded), as one strand set.
io::StrandSet field_strands(fur::FurTrainer& trainer, const fur::Roots& roots, std::uint32_t count, unsigned seed);

// A synth scene's ground truth, sampled for the metrics (`metric_strands`) and for rendering on
// the held-out views (`rendered_strands`, the field's scored count, so both render at one width).
struct FurGroundTruth {
  std::optional<metrics::StrandSample> sample, rendered;
  std::optional<geometry::Mesh> outer;
  std::optional<metrics::ColorTruth> colors;  // when the true strands carry colours
  json info;  // for metrics.json (null without a ground truth)
  // The truth's own scale: the F-scores' thresholds in mm are scene units through it, so a groom
  // made at a wrong scale is judged at the true one (0: no ground truth; the caller's scale then).
  double cm_per_unit = 0;
  metrics::GroomTruth truth() const { return {sample ? &*sample : nullptr, outer ? &*outer : nullptr}; }
  double scale_or(double cm) const { return cm_per_unit > 0 ? cm_per_unit : cm; }
};
FurGroundTruth read_fur_ground_truth(const std::filesystem::path& scene_dir, const FurSettings& s, std::uint32_t rendered_strands, double cm);

// fur.truth: the earlier stages' results swapped for the scene's ground truth through the code
// those stages run, at the same number of roots. Changes `bald`, `vertex_fur`, `data` and `cm` as
// the setting says; returns the swapped inputs (their frames draw more roots), or nothing for
// truth=none.
std::optional<fur::GroundTruthInputs> swap_in_truth(gpu::Context& gpu, const std::filesystem::path& scene_dir, const FurSettings& s,
                                                    geometry::Mesh& bald, defur::VertexFur& vertex_fur, fur::FurTrainingData& data,
                                                    double& cm);

// curve.jsonl: the groom's held-out scores and, with a ground truth, its F-scores against the
// truth, before the first step, every curve_seconds of training, and at the end. Its points are
// kept beside the checkpoint, so a resumed run keeps the points up to the checkpoint's step.
class FurCurve {
 public:
  FurCurve(const FurSettings& s, const std::filesystem::path& resume_file, const FurGroundTruth& truth, double cm);
  bool enabled() const;
  // After a (possibly resumed) trainer is set up: reads the kept points or takes the first.
  void start(fur::FurTrainer& trainer, const fur::FurTrainingData& data, const io::Scene& scene, bool resumed);
  // After each step: a point when curve_seconds of training have passed since the last.
  void after_step(fur::FurTrainer& trainer, const fur::FurTrainingData& data, const io::Scene& scene, double seconds);
  // At the end: the last point (unless taken at this step); writes `file`.
  void finish(fur::FurTrainer& trainer, const fur::FurTrainingData& data, const io::Scene& scene, const std::filesystem::path& file);
  json points() const;

 private:
  void add_point(fur::FurTrainer& trainer, const fur::FurTrainingData& data, const io::Scene& scene);
  const FurSettings& s_;
  std::filesystem::path resume_file_;
  const FurGroundTruth& truth_;
  double cm_;
  std::string lines_;
  double next_ = 0;
  std::uint32_t last_step_ = 0;
};

}  // namespace nf::pipeline
