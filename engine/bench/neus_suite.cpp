#include "engine/bench/neus_suite.hpp"

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "engine/bench/record.hpp"
#include "engine/core/log.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/scene.hpp"
#include "engine/metrics/surface_metrics.hpp"
#include "engine/neus/neus_quality.hpp"
#include "engine/neus/neus_trainer.hpp"
#include "engine/neus/ray_sampling.hpp"
#include "engine/neus/surface_extraction.hpp"
#include "engine/synth/synth_scene.hpp"

namespace nf::bench {
namespace {

constexpr const char* kSuite = "neus";

// Deletes the bench's temporary scene however the suite ends.
struct TempFolder {
  std::filesystem::path path;
  ~TempFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

// CPU ray selection (the shares the trainer uses) for 100,000 rays: the pool of mask classes is
// built once per scene, then every step draws its rays (and clips them to the hull) from it.
json ray_sampling_record(gpu::Context& ctx, const neus::NeusTrainingData& data, const neus::RaySampleOptions& shares,
                         const Options& options) {
  const neus::RayPool pool = neus::build_ray_pool(data.scene, data.masks);
  const std::uint32_t count = 100000;
  std::vector<neus::Ray> rays;
  unsigned seed = 1;
  const Timing timing = time_repeats(options.quick ? 3 : 10, nullptr, [&] {
    rays = neus::sample_rays(pool, data.scene, data.norm, &data.hull, count, seed++, shares);
    return -1.0;
  });
  std::array<double, neus::kRayClassCount> share{};
  std::size_t hits = 0;
  for (const neus::Ray& r : rays) share[r.cls] += 1.0 / double(rays.size()), hits += r.hit();
  const json params{{"rays", count}, {"views", data.scene.cameras.size()},
                    {"hull", {data.hull.dims.x, data.hull.dims.y, data.hull.dims.z}}};
  const json metrics{{"rays_per_second", count / timing.median()},
                     {"share_inside", share[0]}, {"share_band", share[1]}, {"share_background", share[2]},
                     {"share_hitting_the_hull", double(hits) / double(rays.size())}};
  return make_record(ctx, kSuite, "ray_sampling", params, timing, metrics);
}

}  // namespace

json run_neus_suite(gpu::Context& ctx, const Options& options) {
  TempFolder scene_dir{std::filesystem::temp_directory_path() / ("nf-bench-neus-" + std::to_string(::getpid()))};
  synth::SynthOptions so;
  so.animal = "cat";
  so.views = options.quick ? 12 : 36;
  so.resolution = options.quick ? 128 : 512;
  so.strands = options.quick ? 20000 : 100000;
  so.overwrite = true;
  std::filesystem::remove_all(scene_dir.path);
  log::info("bench neus: making the synthetic cat (", so.views, " views, ", so.resolution, "^2)");
  const json gt = synth::synthesize_scene(scene_dir.path, so);
  const double cm_per_unit = gt.at("cm_per_unit").get<double>();
  const geometry::Mesh reference = io::read_mesh(scene_dir.path / "gt" / "outer.ply");

  const neus::NeusQuality quality = neus::quality_preset("draft");
  neus::NeusTrainingOptions training = quality.training;
  const double budget_s = options.quick ? 20.0 : 900.0;  // the 15 minutes on 2 lavapipe cores
  const int eval_resolution = options.quick ? 96 : 160;
  const double eval_every_s = options.quick ? 15.0 : 60.0;

  const io::Scene scene = io::read_scene(scene_dir.path);
  const neus::NeusTrainingData data = neus::load_neus_training_data(scene, quality.hull, quality.hold_out_every);
  glm::dvec3 lo, hi;
  data.hull.occupied_bounds(lo, hi);
  const double diagonal_mm = glm::length(hi - lo) * cm_per_unit * 10.0;

  json records = json::array({ray_sampling_record(ctx, data, quality.training.ray_options, options)});
  const metrics::SurfaceMetrics hull_metrics =
      metrics::surface_metrics(neus::hull_surface(neus::carve_visual_hull(scene, quality.hull)), reference, cm_per_unit, 5.0, 50000, 1);
  log::info("bench neus: the visual hull alone: chamfer ", hull_metrics.chamfer_mean_mm, " mm (",
            100.0 * hull_metrics.chamfer_mean_mm / diagonal_mm, " % of the diagonal)");
  neus::NeusTrainer trainer(ctx, data, quality.field, training);
  json points = json::array(), evaluations = json::array();
  double next_eval = 0.0;
  neus::NeusStepReport last;
  const auto evaluate = [&](const neus::NeusStepReport& r) {
    const geometry::Mesh mesh = neus::extract_surface(trainer.field(), data.norm, data.hull, eval_resolution);
    if (mesh.triangle_count() == 0) return;
    const metrics::SurfaceMetrics m = metrics::surface_metrics(mesh, reference, cm_per_unit, 5.0, 50000, 1);
    const double pct = 100.0 * m.chamfer_mean_mm / diagonal_mm;
    points.push_back({r.seconds, pct});
    evaluations.push_back({{"step", r.step},
                           {"seconds", r.seconds},
                           {"chamfer_mean_mm", m.chamfer_mean_mm},
                           {"chamfer_max_mm", m.chamfer_max_mm},
                           {"chamfer_pct_diagonal", pct},
                           {"normal_consistency", m.normal_consistency},
                           {"psnr_train_rays", r.psnr},
                           {"loss", r.loss},
                           {"inv_s", r.inv_s}});
    log::info("bench neus: step ", r.step, " at ", r.seconds, " s: chamfer ", m.chamfer_mean_mm, " mm (", pct,
              " % of the diagonal), normal consistency ", m.normal_consistency);
  };
  trainer.train(training.steps, {}, [&](const neus::NeusStepReport& r) {
    last = r;
    if (r.seconds >= next_eval) {
      evaluate(r);
      next_eval = r.seconds + eval_every_s;
    }
    return r.seconds < budget_s;
  });
  evaluate(last);

  Timing timing;
  timing.seconds = {last.seconds};
  double reached_1pct = -1;
  for (const json& e : evaluations)
    if (e["chamfer_pct_diagonal"].get<double>() <= 1.0) {
      reached_1pct = e["seconds"].get<double>();
      break;
    }
  const json params{{"animal", so.animal},     {"views", so.views},
                    {"resolution", so.resolution}, {"quality", "draft"},
                    {"steps_done", last.step},   {"rays_per_step", training.rays},
                    {"samples_per_ray", training.samples_per_ray}, {"eval_resolution", eval_resolution},
                    {"budget_s", budget_s}};
  json metrics{{"steps_per_second", last.step / std::max(1e-9, last.seconds)},
               {"rays_per_second", last.step * double(training.rays) / std::max(1e-9, last.seconds)},
               {"box_diagonal_mm", diagonal_mm},
               {"seconds_to_1pct_chamfer", reached_1pct},
               {"visual_hull_chamfer_mean_mm", hull_metrics.chamfer_mean_mm},
               {"visual_hull_chamfer_pct_diagonal", 100.0 * hull_metrics.chamfer_mean_mm / diagonal_mm},
               {"evaluations", evaluations}};
  if (!evaluations.empty()) {
    metrics["final_chamfer_mean_mm"] = evaluations.back()["chamfer_mean_mm"];
    metrics["final_chamfer_pct_diagonal"] = evaluations.back()["chamfer_pct_diagonal"];
    metrics["final_normal_consistency"] = evaluations.back()["normal_consistency"];
  }
  json record = make_record(ctx, kSuite, "draft_cat_training", params, timing, metrics);
  record["curve"] = {{"x", "training seconds"}, {"y", "chamfer mean, % of box diagonal"}, {"points", points}};
  records.push_back(record);
  return records;
}

}  // namespace nf::bench
