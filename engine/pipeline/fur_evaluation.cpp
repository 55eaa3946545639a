#include "engine/pipeline/fur_evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/pipeline/fur_stage.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;

namespace {

HeldOutScores score_held_out(const std::vector<fur::FurView>& views, const io::Scene& scene,
                             const std::function<std::vector<float>(const fur::FurView&)>& render, std::vector<std::vector<float>>* images,
                             const std::function<void()>& before_each) {
  HeldOutScores h;
  for (const fur::FurView& v : views) {
    if (before_each) before_each();
    std::vector<float> image = render(v);
    const fur::ViewScore score = fur::score_view(v, image);
    h.views.push_back({{"camera", scene.cameras[v.camera].name}, {"silhouette_iou", score.silhouette_iou},
                       {"orientation_error_deg", score.orientation_error_deg}, {"pixels", score.pixels}});
    h.silhouette_iou += score.silhouette_iou / double(views.size());
    h.orientation_error_deg += score.orientation_error_deg / double(views.size());
    if (images) images->push_back(std::move(image));
  }
  return h;
}

}  // namespace

json held_out_json(const HeldOutScores& h) { return {{"silhouette_iou", h.silhouette_iou}, {"orientation_error_deg", h.orientation_error_deg}}; }

HeldOutScores score_field_held_out(fur::FurTrainer& trainer, const std::vector<fur::FurView>& views, const io::Scene& scene,
                                   std::uint32_t strands, unsigned seed, std::vector<std::vector<float>>* images,
                                   const std::function<void()>& before_each) {
  return score_held_out(views, scene, [&](const fur::FurView& v) { return trainer.render(v, strands, seed); }, images, before_each);
}

HeldOutScores score_strands_held_out(fur::FurTrainer& trainer, const std::vector<fur::FurView>& views, const io::Scene& scene,
                                     const std::vector<float>& points, const std::function<void()>& before_each) {
  return score_held_out(views, scene, [&](const fur::FurView& v) { return trainer.render_strands(v, points); }, nullptr, before_each);
}

io::StrandSet field_strands(fur::FurTrainer& trainer, const fur::Roots& roots, std::uint32_t count, unsigned seed) {
  std::vector<std::uint32_t> ids = fur::sample_indices(roots.size(), count, seed);
  std::sort(ids.begin(), ids.end());
  std::vector<float> xyz;
  xyz.reserve(ids.size() * fur::kStrandPoints * 3);
  trainer.field().infer(roots, ids, 65536, [&](std::size_t, std::uint32_t, const std::vector<float>& points, const std::vector<float>&) {
    xyz.insert(xyz.end(), points.begin(), points.end());
  });
  return io::StrandSet::uniform(std::uint32_t(ids.size()), fur::kStrandPoints, std::move(xyz));
}

FurGroundTruth read_fur_ground_truth(const fs::path& scene_dir, const FurSettings& s, std::uint32_t rendered_strands, double cm) {
  FurGroundTruth g;
  const auto gt = io::find_ground_truth(scene_dir);
  if (!gt) return g;
  if (fs::exists(gt->strands())) {
    const io::StrandSet hair = io::read_hair(gt->strands());
    g.sample = metrics::sample_strands(hair, s.metric_strands, s.metric_points, 2);
    g.rendered = metrics::sample_strands(hair, rendered_strands, fur::kStrandPoints, 3);
    if (!hair.colors.empty()) g.colors = metrics::color_truth(hair);
  }
  if (fs::exists(gt->outer())) g.outer = io::read_mesh(gt->outer());
  g.info = {{"strands", "gt/strands.hair"}, {"outer", "gt/outer.ply"}, {"cm_per_unit", gt->cm_per_unit}};
  g.cm_per_unit = gt->cm_per_unit;
  if (std::abs(gt->cm_per_unit - cm) > 1e-3 * gt->cm_per_unit)
    log::warn("fur: the knowledge's scale (", cm, " cm per unit) differs from the ground truth's (", gt->cm_per_unit,
              "); the scores against the truth use the truth's");
  return g;
}

std::optional<fur::GroundTruthInputs> swap_in_truth(gpu::Context& gpu, const fs::path& scene_dir, const FurSettings& s, geometry::Mesh& bald,
                                                    defur::VertexFur& vertex_fur, fur::FurTrainingData& data, double& cm) {
  if (s.truth == "none") return std::nullopt;
  fur::GroundTruthInputOptions gi;
  gi.roots = std::max<std::uint64_t>(1, data.roots.size()), gi.hold_out_every = s.hold_out_every, gi.seed = s.training.seed;
  gi.bald = s.truth == "knowledge" ? &bald : nullptr;
  gi.make_views = false;
  std::optional<fur::GroundTruthInputs> swapped = fur::ground_truth_inputs(gpu, scene_dir, gi);
  cm = swapped->data.cm_per_unit;
  vertex_fur = swapped->vertex_fur;
  if (s.truth == "all") {
    bald = swapped->bald;
    data = std::move(swapped->data);
  } else {
    data.roots = std::move(swapped->data.roots);
  }
  log::info("fur: truth=", s.truth, ": the ", s.truth == "all" ? "true bald body, knowledge and roots" : "true knowledge on the pipeline's M_bald",
            " (", data.roots.size(), " roots, ", cm, " cm per unit)");
  return swapped;
}

FurCurve::FurCurve(const FurSettings& s, const fs::path& resume_file, const FurGroundTruth& truth, double cm)
    : s_(s), resume_file_(resume_file), truth_(truth), cm_(cm) {}

bool FurCurve::enabled() const { return s_.curve_seconds > 0; }

void FurCurve::add_point(fur::FurTrainer& trainer, const fur::FurTrainingData& data, const io::Scene& scene) {
  // Scoring is not training time: the x axis is the trainer's own clock.
  const Stopwatch t;
  const std::uint32_t scored = s_.score_strands ? s_.score_strands : s_.training.strands;
  const HeldOutScores held = score_field_held_out(trainer, data.scored_views(), scene, scored, s_.training.seed + 7, nullptr);
  json p{{"step", trainer.step()}, {"seconds", trainer.step() ? trainer.last_report().seconds : 0.0}, {"held_out", held_out_json(held)}};
  if (trainer.step()) p["loss"] = trainer.last_report().loss;
  const metrics::GroomTruth truth = truth_.truth();
  if (truth.strands || truth.outer) {
    // The same subset of the roots at every point, so that the points differ only by the training.
    const io::StrandSet groom = field_strands(trainer, data.roots, s_.metric_strands, s_.training.seed + 13);
    const json scores = metrics::groom_scores(metrics::sample_strands(groom, s_.metric_strands, s_.metric_points, 1), truth, cm_);
    for (const char* key : {"fscore", "tips_to_outer"})
      if (scores.contains(key)) p[key] = scores[key];
  }
  p["scoring_seconds"] = t.seconds();
  lines_ += p.dump() + "\n";
  write_file_atomic(resume_file_, lines_);
  last_step_ = trainer.step();
  next_ = (std::floor(p["seconds"].get<double>() / s_.curve_seconds) + 1) * s_.curve_seconds;
  if (p.contains("fscore"))
    log::info("fur: curve at ", p["seconds"].get<double>(), " s (step ", trainer.step(), "): F(2 cm, 20 deg) ", p["fscore"].value("2cm_20deg", 0.0),
              ", F(2 mm, 20 deg) ", p["fscore"].value("2mm_20deg", 0.0), ", held-out orientation ",
              p["held_out"]["orientation_error_deg"].get<double>(), " deg");
}

void FurCurve::start(fur::FurTrainer& trainer, const fur::FurTrainingData& data, const io::Scene& scene, bool resumed) {
  if (!enabled()) return;
  if (resumed)
    if (std::ifstream in(resume_file_); in) {
      // Points taken after the checkpoint's step are taken again.
      std::istringstream lines(std::string(std::istreambuf_iterator<char>(in), {}));
      for (std::string line; std::getline(lines, line);) {
        const json p = json::parse(line, nullptr, false);
        if (!p.is_object() || !p.contains("seconds") || !p["seconds"].is_number() || !p.contains("step") || !p["step"].is_number_unsigned())
          throw InputError(resume_file_.string() + ": not a curve; delete it to start the curve anew");
        if (p["step"].get<std::uint32_t>() > trainer.step()) break;
        lines_ += line + "\n";
        last_step_ = p["step"].get<std::uint32_t>();
        next_ = (std::floor(p["seconds"].get<double>() / s_.curve_seconds) + 1) * s_.curve_seconds;
      }
    }
  if (lines_.empty()) add_point(trainer, data, scene);
}

void FurCurve::after_step(fur::FurTrainer& trainer, const fur::FurTrainingData& data, const io::Scene& scene, double seconds) {
  if (enabled() && seconds >= next_) add_point(trainer, data, scene);
}

void FurCurve::finish(fur::FurTrainer& trainer, const fur::FurTrainingData& data, const io::Scene& scene, const fs::path& file) {
  if (!enabled()) return;
  if (last_step_ != trainer.step()) add_point(trainer, data, scene);
  write_file_atomic(file, lines_);
}

json FurCurve::points() const {
  json curve = json::array();
  std::istringstream lines(lines_);
  for (std::string line; std::getline(lines, line);) curve.push_back(json::parse(line));
  return curve;
}

}  // namespace nf::pipeline
