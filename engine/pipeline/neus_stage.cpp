#include "engine/pipeline/neus_stage.hpp"

#include <chrono>
#include <cmath>
#include <fstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/progress.hpp"
#include "engine/gpu/context.hpp"
#include "engine/io/mesh.hpp"
#include "engine/metrics/surface_metrics.hpp"
#include "engine/neus/neus_quality.hpp"
#include "engine/neus/surface_extraction.hpp"
#include "engine/nn/weights_io.hpp"
#include "engine/pipeline/neus_previews.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr int kStageVersion = 1;

struct NeusSettings {
  neus::NeusQuality quality;
};

NeusSettings settings_of(const StageContext& c) {
  NeusSettings s{neus::quality_preset(c.quality)};
  const json overrides = c.settings.value("neus", json::object());
  neus::NeusTrainingOptions& t = s.quality.training;
  for (const auto& [key, value] : overrides.items()) {
    const auto count = [&, k = key, v = value]() -> std::uint32_t {
      if (!v.is_number_unsigned() || v.get<std::uint64_t>() > 0xffffffffull)
        throw InputError("neus setting '" + k + "' must be a non-negative integer, got " + v.dump());
      return v.get<std::uint32_t>();
    };
    const auto real = [&, k = key, v = value]() -> float {
      if (!v.is_number() || !std::isfinite(v.get<double>()))
        throw InputError("neus setting '" + k + "' must be a number, got " + v.dump());
      return v.get<float>();
    };
    if (key == "steps") t.steps = count();
    else if (key == "rays") t.rays = count();
    else if (key == "samples_per_ray") t.samples_per_ray = count();
    else if (key == "fine_samples") t.fine_samples = count();
    else if (key == "seed") t.seed = count();
    else if (key == "hull_fit_steps") t.hull_fit_steps = count();
    else if (key == "lr") t.lr = real();
    else if (key == "variance_lr") t.variance_lr = real();
    else if (key == "sharpness") t.sharpness = real();
    else if (key == "max_scheduled_inv_s") t.max_scheduled_inv_s = real();
    else if (key == "colour_weight") t.weights.colour = real();
    else if (key == "mask_weight") t.weights.mask = real();
    else if (key == "eikonal_weight") t.eikonal = real();
    else if (key == "mesh_resolution") s.quality.mesh_resolution = int(count());
    else if (key == "hull_resolution") s.quality.hull.resolution = int(count());
    else
      throw InputError("neus setting '" + key + "' is unknown (steps, rays, samples_per_ray, fine_samples, seed, "
                       "hull_fit_steps, lr, variance_lr, sharpness, max_scheduled_inv_s, colour_weight, mask_weight, "
                       "eikonal_weight, mesh_resolution, hull_resolution)");
  }
  t.validate();
  return s;
}

json cameras_json(const io::Scene& scene) {
  json cams = json::array();
  for (const io::Camera& c : scene.cameras) {
    json m = json::array();
    for (int col = 0; col < 4; ++col)
      for (int row = 0; row < 4; ++row) m.push_back(c.camera_to_world[col][row]);
    cams.push_back({{"name", c.name},
                    {"size", {c.width, c.height}},
                    {"f", {c.fx, c.fy}},
                    {"c", {c.cx, c.cy}},
                    {"pose", m},
                    {"image", c.image.filename().string()},
                    {"mask", c.mask.filename().string()}});
  }
  return cams;
}

// Ground truth when the scene is an `nf_gpu synth` scene: gt/outer.ply and gt/scene.json.
json ground_truth_metrics(const StageContext& c, const io::Mesh& mesh, const neus::NeusTrainingData& data) {
  const fs::path outer = c.scene_dir / "gt" / "outer.ply", info = c.scene_dir / "gt" / "scene.json";
  if (!fs::exists(outer) || !fs::exists(info) || mesh.triangle_count() == 0) return json();
  std::ifstream in(info);
  const json scene = json::parse(in, nullptr, false);
  if (!scene.is_object() || !scene.contains("cm_per_unit")) return json();
  const double cm = scene["cm_per_unit"].get<double>();
  const metrics::SurfaceMetrics m = metrics::surface_metrics(mesh, io::read_mesh(outer), cm);
  glm::dvec3 lo, hi;
  data.hull.occupied_bounds(lo, hi);
  const double diagonal_mm = glm::length(hi - lo) * cm * 10.0, pct = 100.0 * m.chamfer_mean_mm / diagonal_mm;
  log::info("neus: chamfer against gt/outer.ply ", m.chamfer_mean_mm, " mm (", pct, " % of the box diagonal)");
  json j = metrics::to_json(m);
  j["box_diagonal_mm"] = diagonal_mm;
  j["chamfer_mean_pct_diagonal"] = pct;
  j["reference"] = "gt/outer.ply";
  return j;
}

}  // namespace

std::vector<fs::path> NeusStage::inputs(const StageContext& c) const {
  std::vector<fs::path> files;
  for (const io::Camera& cam : c.scene.cameras) {
    if (!cam.image.empty()) files.push_back(cam.image);
    if (!cam.mask.empty()) files.push_back(cam.mask);
  }
  for (const char* gt : {"gt/outer.ply", "gt/scene.json"})  // synth scenes: metrics.json compares with them
    if (fs::exists(c.scene_dir / gt)) files.push_back(c.scene_dir / gt);
  return files;
}

json NeusStage::parameters(const StageContext& c) const {
  const NeusSettings s = settings_of(c);
  const neus::VisualHullOptions& h = s.quality.hull;
  return {{"stage_version", kStageVersion},
          {"quality", c.quality},
          {"field", neus::to_json(s.quality.field)},
          {"training", neus::to_json(s.quality.training)},
          {"hull", {h.resolution, h.coarse_resolution, h.dilate_px, h.min_views, h.margin_cells}},
          {"hold_out_every", s.quality.hold_out_every},
          {"mesh_resolution", s.quality.mesh_resolution},
          {"cameras", cameras_json(c.scene)}};
}

json NeusStage::run(StageContext& c, const fs::path& out, const fs::path& resume) {
  const NeusSettings s = settings_of(c);
  const neus::NeusQuality& q = s.quality;
  const auto t0 = std::chrono::steady_clock::now();
  const neus::NeusTrainingData data = neus::load_neus_training_data(c.scene, q.hull, q.hold_out_every);
  log::info("neus: ", data.train_views.size(), " training views, ", data.held_out_views.size(), " held out; ",
            q.training.steps, " steps of ", q.training.rays, " rays x ", q.training.samples_per_ray, " samples");
  auto trainer = std::make_unique<neus::NeusTrainer>(c.gpu, data, q.field, q.training);
  const fs::path checkpoint = resume / "checkpoint.nfwt";
  if (fs::exists(checkpoint)) {
    bool resumed = false;
    try {
      resumed = trainer->load_checkpoint(checkpoint);
    } catch (const InputError& e) {
      log::warn("neus: ", e.what(), "; starting afresh");
      trainer = std::make_unique<neus::NeusTrainer>(c.gpu, data, q.field, q.training);
    }
    if (resumed)
      log::info("neus: resuming from ", checkpoint.string(), " at step ", trainer->step());
    else
      fs::remove(checkpoint);
  }
  Progress progress("neus", q.training.steps);
  trainer->train(q.training.steps, checkpoint, [&](const neus::NeusStepReport& r) {
    char status[160];
    std::snprintf(status, sizeof status, "loss %.4f psnr %.1f inv_s %.0f %.0f rays/s", r.loss, r.psnr, r.inv_s,
                  r.rays_per_second);
    progress.update(r.step, status);
    return true;
  });
  progress.finish();
  std::string curve;
  for (const neus::NeusStepReport& r : trainer->history()) curve += neus::to_json(r).dump() + "\n";
  write_file_atomic(out / "training.jsonl", curve);
  const neus::NeusStepReport last = trainer->last_report();
  const double train_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // The model: the field's tensors, its configuration and the normalisation to scene units.
  nn::WeightsFile model;
  model.config = {{"kind", "neus model"}, {"field", neus::to_json(q.field)}, {"normalisation", neus::to_json(data.norm)},
                  {"inv_s", trainer->inv_s()}, {"steps", trainer->step()}};
  for (auto& [name, values] : trainer->field().save_parameters()) {
    const std::uint64_t n = values.size();
    model.tensors.push_back({name, {n}, std::move(values)});
  }
  nn::save_weights(out / "model.nfwt", model);
  write_file_atomic(out / "normalisation.json", neus::to_json(data.norm).dump(2) + "\n");

  const auto t1 = std::chrono::steady_clock::now();
  neus::SurfaceGridStats grid;
  const io::Mesh mesh = neus::extract_surface(trainer->field(), data.norm, data.hull, q.mesh_resolution, &grid);
  if (mesh.triangle_count() == 0)
    throw InputError("neus: the trained surface is empty (no zero crossing inside the visual hull); check the masks "
                     "and cameras of " + c.scene_dir.string());
  io::write_mesh_ply(out / "outer.ply", mesh);
  const double mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();

  const std::vector<std::uint32_t> preview_views =
      data.held_out_views.empty() ? std::vector<std::uint32_t>{data.train_views.front()} : data.held_out_views;
  const json previews = render_neus_previews(trainer->field(), data, mesh, preview_views,
                                             trainer->finite_difference_step(), out / "renders");
  json summary{{"steps", trainer->step()},
               {"train_seconds", train_seconds},
               {"mesh_seconds", mesh_seconds},
               {"final", {{"loss", last.loss}, {"psnr_train_rays", last.psnr}, {"inv_s", last.inv_s}}},
               {"skipped_steps", last.skipped_steps},
               {"mesh", {{"vertices", mesh.vertex_count()},
                         {"triangles", mesh.triangle_count()},
                         {"grid", {grid.dims.x, grid.dims.y, grid.dims.z}},
                         {"evaluated_points", grid.evaluated},
                         {"components", grid.components}}},
               {"held_out", previews},
               {"peak_device_bytes", c.gpu.peak_allocated_bytes()}};
  const json gt = ground_truth_metrics(c, mesh, data);
  if (!gt.is_null()) summary["ground_truth"] = gt;
  write_file_atomic(out / "metrics.json", summary.dump(2) + "\n");
  return summary;
}

}  // namespace nf::pipeline
