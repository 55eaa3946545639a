#include "engine/pipeline/neus_stage.hpp"

#include <chrono>
#include <cmath>
#include <fstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/core/log.hpp"
#include "engine/core/output_guard.hpp"
#include "engine/core/progress.hpp"
#include "engine/gpu/context.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/io/mesh.hpp"
#include "engine/metrics/surface_metrics.hpp"
#include "engine/neus/envelope_input.hpp"
#include "engine/neus/neus_previews.hpp"
#include "engine/neus/surface_extraction.hpp"
#include "engine/nn/weights_io.hpp"
#include "engine/pipeline/checkpoint.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr int kStageVersion = 1;


// Ground truth when the scene is an `nf_gpu synth` scene: chamfer against its fur envelope.
json ground_truth_metrics(const StageContext& c, const geometry::Mesh& mesh, const neus::OccupancyGrid& hull) {
  const std::optional<io::GroundTruth> gt = io::find_ground_truth(c.scene_dir);
  if (!gt || !fs::exists(gt->outer()) || mesh.triangle_count() == 0) return json();
  const metrics::SurfaceMetrics m = metrics::surface_metrics(mesh, io::read_mesh(gt->outer()), gt->cm_per_unit);
  glm::dvec3 lo, hi;
  hull.occupied_bounds(lo, hi);
  const double diagonal_mm = glm::length(hi - lo) * gt->cm_per_unit * 10.0, pct = 100.0 * m.chamfer_mean_mm / diagonal_mm;
  log::info("neus: chamfer against gt/outer.ply ", m.chamfer_mean_mm, " mm (", pct, " % of the box diagonal)");
  json j = metrics::to_json(m);
  j["box_diagonal_mm"] = diagonal_mm;
  j["chamfer_mean_pct_diagonal"] = pct;
  j["reference"] = "gt/outer.ply";
  return j;
}

// `neus.mesh`: the user's envelope, checked against the masks' visual hull, becomes M_NeuS as it is
// (no field, no renders: later stages read outer.ply only).
json use_envelope_file(const StageContext& c, const neus::NeusQuality& q, const NeusOutputs& out) {
  // The stages replace their folders under WORK: an envelope kept there could vanish under its user.
  if (path_inside(q.mesh, c.work))
    throw UsageError("neus.mesh=" + q.mesh + " lies inside the WORK folder " + c.work.string() +
                     ", whose stage folders nf_gpu replaces; keep your envelope outside it");
  const auto t0 = std::chrono::steady_clock::now();
  neus::EnvelopeInputReport report;
  const geometry::Mesh mesh = neus::read_envelope_input(q.mesh, &report);  // format errors before the carve
  const neus::OccupancyGrid hull = neus::carve_visual_hull(c.scene, q.hull);
  neus::check_envelope_against_hull(mesh, hull, q.mesh, &report);
  io::write_mesh_ply(out.outer(), mesh);
  log::info("neus: M_NeuS from ", q.mesh, " (", report.triangles, " triangles, ", 100.0 * report.inside_hull,
            " % of its surface inside the masks' visual hull); no training");
  json summary{{"source", "file"},
               {"file", fs::absolute(q.mesh).string()},
               {"envelope", neus::to_json(report)},
               {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()}};
  const json gt = ground_truth_metrics(c, mesh, hull);
  if (!gt.is_null()) summary["ground_truth"] = gt;
  write_file_atomic(out.metrics(), summary.dump(2) + "\n");
  return summary;
}

}  // namespace

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

std::vector<fs::path> NeusStage::inputs(const StageContext& c) const {
  std::vector<fs::path> files;
  for (const io::Camera& cam : c.scene.cameras) {
    if (!cam.image.empty()) files.push_back(cam.image);
    if (!cam.mask.empty()) files.push_back(cam.mask);
  }
  const neus::NeusQuality q = settings_of(c);
  if (!q.mesh.empty()) files.push_back(q.mesh);
  if (const auto gt = io::find_ground_truth(c.scene_dir))  // synth scenes: metrics.json compares with them
    for (const fs::path& f : {gt->outer(), gt->scene_json()})
      if (fs::exists(f)) files.push_back(f);
  return files;
}

json NeusStage::parameters(const StageContext& c) const {
  const neus::NeusQuality q = settings_of(c);
  const neus::VisualHullOptions& h = q.hull;
  if (!q.mesh.empty())  // the file's content is an input; training settings do not matter
    return {{"stage_version", kStageVersion},
            {"envelope", "neus.mesh"},
            {"hull", {h.resolution, h.coarse_resolution, h.dilate_px, h.min_views, h.margin_cells}},
            {"cameras", cameras_json(c.scene)}};
  return {{"stage_version", kStageVersion},
          {"quality", c.quality},
          {"field", neus::to_json(q.field)},
          {"training", neus::to_json(q.training)},
          {"hull", {h.resolution, h.coarse_resolution, h.dilate_px, h.min_views, h.margin_cells}},
          {"hold_out_every", q.hold_out_every},
          {"mesh_resolution", q.mesh_resolution},
          {"cameras", cameras_json(c.scene)}};
}

json NeusStage::run(StageContext& c, const fs::path& out_dir, const fs::path& resume) {
  const neus::NeusQuality q = settings_of(c);
  const NeusOutputs out{out_dir};
  if (!q.mesh.empty()) return use_envelope_file(c, q, out);
  const auto t0 = std::chrono::steady_clock::now();
  const neus::NeusTrainingData data = neus::load_neus_training_data(c.scene, q.hull, q.hold_out_every);
  if (interrupted()) throw Interrupted("neus: stopped before the first training step; nothing to save");
  log::info("neus: ", data.train_views.size(), " training views, ", data.held_out_views.size(), " held out; ",
            q.training.steps, " steps of ", q.training.rays, " rays x ", q.training.samples_per_ray, " samples");
  auto trainer = std::make_unique<neus::NeusTrainer>(c.gpu, data, q.field, q.training);
  const fs::path checkpoint = resume / "checkpoint.nfwt";
  if (resume_or_discard(
          "neus", checkpoint, [&] { return trainer->load_checkpoint(checkpoint); },
          [&] { trainer = std::make_unique<neus::NeusTrainer>(c.gpu, data, q.field, q.training); }))
    log::info("neus: resuming from ", checkpoint.string(), " at step ", trainer->step());
  Progress progress("neus", q.training.steps);
  trainer->train(q.training.steps, checkpoint, [&](const neus::NeusStepReport& r) {
    char status[160];
    std::snprintf(status, sizeof status, "loss %.4f psnr %.1f inv_s %.0f %.0f rays/s", r.loss, r.psnr, r.inv_s,
                  r.rays_per_second);
    progress.update(r.step, status);
    return !interrupted();
  });
  if (interrupted()) {
    trainer->save_checkpoint(checkpoint);
    progress.stop("stopped");
    throw Interrupted("neus: stopped at step " + std::to_string(trainer->step()) + " of " +
                      std::to_string(q.training.steps) + "; checkpoint saved in " + checkpoint.string());
  }
  progress.finish();
  std::string curve;
  for (const neus::NeusStepReport& r : trainer->history()) curve += neus::to_json(r).dump() + "\n";
  write_file_atomic(out.training(), curve);
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
  nn::save_weights(out.model(), model);
  write_file_atomic(out.normalisation(), neus::to_json(data.norm).dump(2) + "\n");

  const auto t1 = std::chrono::steady_clock::now();
  neus::SurfaceGridStats grid;
  const geometry::Mesh mesh = neus::extract_surface(trainer->field(), data.norm, data.hull, q.mesh_resolution, &grid);
  if (mesh.triangle_count() == 0)
    throw InputError("neus: the trained surface is empty (no zero crossing inside the visual hull); check the masks "
                     "and cameras of " + c.scene_dir.string());
  io::write_mesh_ply(out.outer(), mesh);
  const double mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();

  const std::vector<std::uint32_t> preview_views =
      data.held_out_views.empty() ? std::vector<std::uint32_t>{data.train_views.front()} : data.held_out_views;
  const json previews = neus::render_neus_previews(trainer->field(), data, mesh, preview_views,
                                             trainer->finite_difference_step(), out.renders());
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
  const json gt = ground_truth_metrics(c, mesh, data.hull);
  if (!gt.is_null()) summary["ground_truth"] = gt;
  write_file_atomic(out.metrics(), summary.dump(2) + "\n");
  return summary;
}

const SettingsSchema<neus::NeusQuality>& neus_settings() {
  using Q = neus::NeusQuality;
  static const SettingsSchema<Q> schema = [] {
    SettingsSchema<Q> s("neus", [](const std::string& quality) { return neus::quality_preset(quality); });
    s.add("steps", [](Q& q) -> auto& { return q.training.steps; }, 1, 1e8, "training steps")
        .add("rays", [](Q& q) -> auto& { return q.training.rays; }, 1, 1 << 20, "rays per step")
        .add("samples_per_ray", [](Q& q) -> auto& { return q.training.samples_per_ray; }, 2, 1024,
             "samples per ray, coarse and fine together (rays x samples_per_ray at most 2^22)")
        .add("fine_samples", [](Q& q) -> auto& { return q.training.fine_samples; }, 0, 1023,
             "of samples_per_ray, placed by NeuS up-sampling near the surface; below samples_per_ray (0: all stratified)")
        .add("seed", [](Q& q) -> auto& { return q.training.seed; }, 0, 4294967295.0, "random seed (rays, samples, initialisation)")
        .add("hull_fit_steps", [](Q& q) -> auto& { return q.training.hull_fit_steps; }, 0, 1e6,
             "steps fitting the SDF to the visual hull before rendering starts (0: start from a sphere)")
        .add("lr", [](Q& q) -> auto& { return q.training.lr; }, 1e-7, 1, "learning rate of the hash table and the networks (warm-up, then cosine decay)")
        .add("variance_lr", [](Q& q) -> auto& { return q.training.variance_lr; }, 0, 1, "learning rate of the inverse variance")
        .add("sharpness", [](Q& q) -> auto& { return q.training.sharpness; }, 0, 100,
             "inv_s is kept at least sharpness / h (h: the finite-difference step); 0: learned only")
        .add("max_scheduled_inv_s", [](Q& q) -> auto& { return q.training.max_scheduled_inv_s; }, 0, 1e6,
             "the cap of that floor")
        .add("colour_weight", [](Q& q) -> auto& { return q.training.weights.colour; }, 0, 1e6, "weight of the colour L1 loss (rays inside the masks)")
        .add("mask_weight", [](Q& q) -> auto& { return q.training.weights.mask; }, 0, 1e6, "weight of the mask binary cross-entropy (every ray)")
        .add("eikonal_weight", [](Q& q) -> auto& { return q.training.eikonal; }, 0, 1e6, "weight of the Eikonal loss")
        .add("checkpoint_interval", [](Q& q) -> auto& { return q.training.checkpoint_interval; }, 0, 1e8,
             "steps between checkpoints (0: none; Ctrl-C always saves one)")
        .add("mesh_resolution", [](Q& q) -> auto& { return q.mesh_resolution; }, 8, 2048,
             "marching-cubes cells along the longest axis of the hull's box")
        .add("hull_resolution", [](Q& q) -> auto& { return q.hull.resolution; }, 8, 2048,
             "visual-hull cells along the longest axis of its box")
        .text("mesh", [](Q& q) -> auto& { return q.mesh; }, {},
              "an envelope of your own (PLY, OBJ or glTF in the scene's frame and units, e.g. a scan) used as M_NeuS instead of training")
        .check([](const Q& q) {
          q.training.validate();
          // The format is io::read_mesh's to judge, when the stage reads the file.
          if (!q.mesh.empty() && !fs::is_regular_file(q.mesh)) throw UsageError("neus.mesh=" + q.mesh + ": no such file");
        });
    return s;
  }();
  return schema;
}

}  // namespace nf::pipeline
