#include "engine/pipeline/body_stage.hpp"

#include <chrono>
#include <cmath>
#include <limits>

#include "engine/body/posing.hpp"
#include "engine/body/body_measures.hpp"
#include "engine/body/photo_eyes.hpp"
#include "engine/body/region_transfer.hpp"
#include "engine/body/smal_model.hpp"
#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/core/log.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/io/mesh.hpp"
#include "engine/pipeline/neus_stage.hpp"
#include "engine/pipeline/preview_views.hpp"
#include "engine/synth/preview.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr int kStageVersion = 12;  // 2: fit.json; 3: the head-and-body length; 4: the eyes from the photos; 5: the tail's pitch tried; 6: several blobs a view, round ones first, the eyes a mirrored pair;
                                  // 7: pads only where M_NeuS faces down; 8: an eye's centre from its blob's area, not its darkness; 9: front and rear legs their own length;
                                  // 10: the eye blob's centre by mean shift, the torso's aspect bounded; 11: labels from the template's finer build; 12: the fit's eyes from it too

// The cameras' mean up vector when they agree on one (a capture rig's usual case).
body::FrameHints frame_hints(const io::Scene& scene) {
  glm::dvec3 sum(0.0);
  for (const io::Camera& c : scene.cameras) sum += glm::normalize(glm::dvec3(c.camera_to_world[1]));
  body::FrameHints hints;
  if (!scene.cameras.empty() && glm::length(sum) > 0.5 * double(scene.cameras.size())) hints.up = glm::normalize(sum);
  return hints;
}

// The eyes: found in the photos and triangulated when every view's detections agree, else the
// fitted template's (with a warning). eyes.json keeps both and how the photos' were found.
struct EyesFound {
  glm::dvec3 left, right;
  json record;
};

EyesFound eyes_of(const io::Scene& scene, const body::BodyModel& model, const body::BodyFit& fit, const std::vector<glm::dvec3>& joints,
                  const body::FittedEyes& fitted, bool from_photos) {
  EyesFound out{fitted.left, fitted.right, json::object()};
  const json fitted_json{{"left", json_vec3(fitted.left)}, {"right", json_vec3(fitted.right)}, {"distance", glm::distance(fitted.left, fitted.right)}};
  out.record = {{"unit", "scene units"}, {"fitted", fitted_json}, {"source", "fit"}};
  const std::optional<body::HeadAxis> head = body::head_axis(model, joints);
  if (from_photos && !head)
    log::warn("body: the body model names no 'head' and 'muzzle' joints, so the eyes are not searched in the photos");
  if (from_photos && head) {
    // The eyeball's radius: the eye region's mean distance from its centre, on each side.
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t v = 0; v < fit.fitted.vertex_count(); ++v)
      if (fit.fitted.regions[v] == body::region_id(body::Region::eyes)) {
        const glm::dvec3 p(fit.fitted.position(v));
        sum += std::min(glm::distance(p, fitted.left), glm::distance(p, fitted.right)), ++n;
      }
    const body::EyeSearch search{fitted.left, fitted.right, head->centre, n ? sum / double(n) : 0.0};
    const body::PhotoEyes found = body::find_eyes_in_photos(scene, search);
    out.record["photos"] = {{"left", body::to_json(found.left, scene.cameras)},
                            {"right", body::to_json(found.right, scene.cameras)},
                            {"views_facing", found.views_facing},
                            {"eye_radius", search.eye_radius}};
    for (int e = 0; e < 2; ++e) {
      json& list = out.record["photos"]["hypotheses"][e == 0 ? "left" : "right"] = json::array();
      for (const body::TriangulatedPoint& t : found.hypotheses[e]) list.push_back(body::to_json(t, scene.cameras));
    }
    if (found.distance()) {
      out.left = *found.left.position, out.right = *found.right.position;
      out.record["source"] = "photos";
      log::info("body: the eyes found in the photos: ", found.left.views.size(), " and ", found.right.views.size(), " views, ",
                found.left.reprojection_rms_px, " and ", found.right.reprojection_rms_px, " px reprojection error; ",
                *found.distance(), " units apart (the fit's ", glm::distance(fitted.left, fitted.right), ")");
    } else {
      log::warn("body: the eyes were not found in the photos (left: ", found.left.reason.empty() ? "found" : found.left.reason,
                "; right: ", found.right.reason.empty() ? "found" : found.right.reason, "): the fitted template's eyes stand");
    }
  }
  out.record["left"] = json_vec3(out.left);
  out.record["right"] = json_vec3(out.right);
  out.record["distance"] = glm::distance(out.left, out.right);
  return out;
}

json ground_truth_metrics(const StageContext& c, const geometry::Mesh& labelled, const body::FittedEyes& fitted, const EyesFound& eyes) {
  const std::optional<io::GroundTruth> gt = io::find_ground_truth(c.scene_dir);
  if (!gt || !fs::exists(gt->bald())) return json();
  const geometry::Mesh bald = io::read_mesh(gt->bald());
  const body::RegionAccuracy accuracy = body::region_accuracy(labelled, bald);
  json out = body::to_json(accuracy);
  out["reference"] = "gt/bald.ply";
  const json eyes_gt = gt->info.value("eye_centres", json());
  const auto is_point = [](const json& j) {
    return j.is_array() && j.size() == 3 && j[0].is_number() && j[1].is_number() && j[2].is_number();
  };
  if (eyes_gt.is_object() && is_point(eyes_gt.value("left", json())) && is_point(eyes_gt.value("right", json()))) {
    const auto point = [](const json& j) { return glm::dvec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>()); };
    const double mm = gt->cm_per_unit * 10.0;
    out["eye_error_mm"] = {{"left", glm::distance(eyes.left, point(eyes_gt["left"])) * mm},
                           {"right", glm::distance(eyes.right, point(eyes_gt["right"])) * mm}};
    out["fitted_eye_error_mm"] = {{"left", glm::distance(fitted.left, point(eyes_gt["left"])) * mm},
                                  {"right", glm::distance(fitted.right, point(eyes_gt["right"])) * mm}};
    const double true_distance = glm::distance(point(eyes_gt["left"]), point(eyes_gt["right"]));
    out["eye_distance_error"] = glm::distance(eyes.left, eyes.right) / true_distance - 1.0;
    out["fitted_eye_distance_error"] = glm::distance(fitted.left, fitted.right) / true_distance - 1.0;
    out["eyes_from"] = eyes.record["source"];
  }
  log::info("body: labels on M_NeuS agree with the ground truth on ", 100.0 * accuracy.accuracy, " % of the surface");
  return out;
}

}  // namespace

bool read_eyes_from_photos(const BodyOutputs& o) {
  const json j = io::read_json_file(o.eyes());
  const std::optional<io::JsonField> source = io::JsonField(j, o.eyes().string()).find("source");
  return source && source->string() == "photos";
}

glm::dmat4 read_animal_to_world(const BodyOutputs& o) {
  const json j = io::read_json_file(o.animal_frame());
  return io::matrix_rows(io::JsonField(j, o.animal_frame().string()).at("animal_to_world"));
}

std::optional<double> read_head_and_body_length(const BodyOutputs& o) {
  const json j = io::read_json_file(o.animal_frame());
  const std::optional<io::JsonField> d = io::JsonField(j, o.animal_frame().string()).find("head_and_body_length");
  if (!d || d->value().is_null()) return std::nullopt;
  if (!(std::isfinite(d->number()) && d->number() > 0)) d->fail("expected a positive length");
  return d->number();
}

double read_eye_distance(const BodyOutputs& o) {
  const json j = io::read_json_file(o.eyes());
  const io::JsonField d = io::JsonField(j, o.eyes().string()).at("distance");
  if (!(std::isfinite(d.number()) && d.number() >= 0)) d.fail("expected a distance of 0 or more");
  return d.number();
}

body::BodyModel body_model_of(const BodySettings& s) {
  return s.model.empty() ? body::default_template() : body::load_smal_model(s.model);
}

body::BodyFit read_body_fit(const BodyOutputs& o, const body::BodyModel& model) {
  const json j = io::read_json_file(o.fit_state());
  const io::JsonField root(j, o.fit_state().string());
  body::BodyFit fit;
  fit.fit_to_world = io::matrix_rows(root.at("fit_to_world"));
  const io::JsonField vars = root.at("variables");
  if (!vars.value().is_array()) vars.fail("expected an array of numbers");
  const std::size_t expected = body::PoseLayout::of(model, true).size();
  if (vars.value().size() != expected)
    vars.fail("has " + std::to_string(vars.value().size()) + " values; the body model " + model.name + " needs " +
              std::to_string(expected) + " (was the body stage run with another model?)");
  for (std::size_t i = 0; i < expected; ++i) {
    const json& v = vars.value()[i];
    if (!v.is_number() || !std::isfinite(v.get<double>())) vars.fail("value " + std::to_string(i) + " is not a finite number");
    fit.variables.push_back(v.get<double>());
  }
  fit.animal_to_world = io::matrix_rows(root.at("animal_to_world"));
  return fit;
}

std::vector<fs::path> BodyStage::inputs(const StageContext& c) const {
  std::vector<fs::path> files{neus_outputs(c.work).outer()};
  const BodySettings s = settings_of(c);
  if (!s.model.empty()) files.push_back(s.model);
  if (s.photo_eyes)  // the eyes are searched in the photos
    for (const io::Camera& cam : c.scene.cameras)
      for (const fs::path& f : {cam.image, cam.mask})
        if (!f.empty()) files.push_back(f);
  if (const auto gt = io::find_ground_truth(c.scene_dir))  // synth scenes: metrics.json compares with them
    for (const fs::path& f : {gt->bald(), gt->scene_json()})
      if (fs::exists(f)) files.push_back(f);
  return files;
}

json BodyStage::parameters(const StageContext& c) const {
  json cams = json::array();
  for (const io::Camera& cam : c.scene.cameras) cams.push_back(json_vec3(glm::dvec3(cam.camera_to_world[1])));
  json key = key_of(c, kStageVersion);
  key["camera_ups"] = cams;
  if (settings_of(c).photo_eyes) key["cameras"] = cameras_json(c.scene);  // the eyes are triangulated through them
  return key;
}

json BodyStage::run(StageContext& c, const fs::path& out_dir, const fs::path&) {
  const BodySettings s = settings_of(c);
  const BodyOutputs out{out_dir};
  const auto t0 = std::chrono::steady_clock::now();
  const body::BodyModel model = body_model_of(s);
  const double model_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const fs::path target_file = neus_outputs(c.work).outer();
  geometry::Mesh target = io::read_mesh(target_file);
  log::info("body: fitting ", model.name, " (", model.vertex_count(), " vertices, ", model.joint_count(), " joints, ",
            model.shape_count(), " shapes) to ", target_file.string(), " (", target.vertex_count(), " vertices)");
  const body::FrameHints hints = frame_hints(c.scene);
  if (!hints.up) log::info("body: the cameras do not agree on an up direction; trying every principal axis");
  const body::BodyFit fit = body::fit_body(model, target, hints, s.fit, target_file.string());
  if (interrupted()) throw Interrupted("body: stopped during the fit; it has no checkpoint (it takes seconds)");
  for (const body::FitStageReport& r : fit.stages)
    log::info("body: stage ", r.name, ": chamfer ", r.chamfer_start, " -> ", r.chamfer_end, " scene units in ", r.seconds, " s");

  target.regions = body::nearest_regions(target, body::region_carrier(model, fit.fitted));
  if (target.normals.empty()) geometry::compute_vertex_normals(target);
  const std::size_t sideways_pads = body::pads_face_down(target, glm::dvec3(fit.animal_to_world[1]));
  log::info("body: ", sideways_pads, " vertices of M_NeuS labelled pads do not face down: they take their paw's fur (or leg) instead");
  io::write_mesh_ply(out.outer_regions(), target);
  io::write_mesh_ply(out.fitted(), fit.fitted);

  const std::vector<glm::dvec3> joints = body::fitted_joints(model, fit);
  const body::FittedEyes fitted_eyes = body::fitted_eyes(model, fit);
  const auto t_eyes = std::chrono::steady_clock::now();
  const EyesFound eyes = eyes_of(c.scene, model, fit, joints, fitted_eyes, s.photo_eyes != 0);
  const double eye_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_eyes).count();
  write_file_atomic(out.eyes(), eyes.record.dump(2) + "\n");
  const glm::dmat4& a = fit.animal_to_world;
  const double scale = glm::length(glm::dvec3(a[0]));
  const std::optional<double> body_length = body::head_and_body_length(model, joints);
  if (!body_length)
    log::warn("body: the body model does not name the joints from the nose to the tail's root (nose, muzzle, head, neck, chest, "
              "spine, pelvis, tail_0), so the metric scale has no head-and-body length to go on");
  write_file_atomic(out.animal_frame(), json{{"animal_to_world", json_matrix_rows(a)},
                                             {"head_and_body_length", body_length ? json(*body_length) : json()},
                                             {"origin", json_vec3(glm::dvec3(a[3]))},
                                             {"left", json_vec3(glm::dvec3(a[0]) / scale)},
                                             {"up", json_vec3(glm::dvec3(a[1]) / scale)},
                                             {"forward", json_vec3(glm::dvec3(a[2]) / scale)},
                                             {"scene_units_per_model_unit", scale},
                                             {"axes", "x: the animal's right to left, y: up (against gravity), "
                                                      "z: tail to head"}}
                                            .dump(2) + "\n");

  write_file_atomic(out.fit_state(), json{{"model", model.name},
                                          {"fit_to_world", json_matrix_rows(fit.fit_to_world)},
                                          {"animal_to_world", json_matrix_rows(fit.animal_to_world)},
                                          {"variables", fit.variables}}
                                         .dump() + "\n");
  const body::PoseLayout layout = body::PoseLayout::of(model, true);
  json shape = json::object(), pose = json::object();
  for (std::size_t k = 0; k < model.shape_count(); ++k) shape[model.shape_names[k]] = fit.variables[layout.shape_begin() + k];
  for (std::size_t k = 0; k < model.joint_count(); ++k) {
    const std::size_t i = layout.joint_begin() + 3 * k;
    pose[model.joint_names[k]] = {fit.variables[i], fit.variables[i + 1], fit.variables[i + 2]};
  }
  json stages = json::array();
  for (const body::FitStageReport& r : fit.stages)
    stages.push_back({{"stage", r.name}, {"steps", r.steps}, {"chamfer_start", r.chamfer_start},
                      {"chamfer_end", r.chamfer_end}, {"loss_end", r.loss_end}, {"seconds", r.seconds}});
  double offset_rms = 0;
  for (std::size_t i = layout.offset_begin(); i < layout.size(); ++i) offset_rms += fit.variables[i] * fit.variables[i];
  offset_rms = std::sqrt(offset_rms / double(std::max<std::size_t>(1, model.vertex_count())));
  write_file_atomic(out.params(), json{{"model", model.name},
                                       {"shape", shape},
                                       {"joint_rotations", pose},
                                       {"animal_to_world", json_matrix_rows(a)},
                                       {"offsets_rms_model_units", offset_rms},
                                       {"stages", stages},
                                       {"hypotheses", fit.hypotheses},
                                       {"chamfer_mean", fit.chamfer_mean},
                                       {"relative_chamfer", fit.relative_chamfer},
                                       {"low_confidence", fit.low_confidence},
                                       {"torso_at_bound", fit.torso_at_bound}}
                                      .dump(2) + "\n");
  if (fit.low_confidence)
    log::warn("body: low confidence: the fitted body stays ", 100.0 * fit.relative_chamfer, " % of the surface's radius "
              "from it on average (good quadruped fits stay below 5 %); is the subject a four-legged animal? Region labels "
              "are likely wrong on much of the surface");
  else if (fit.torso_at_bound)
    log::warn("body: the surface is rounder than a quadruped's body (long fur?): the fitted torso's length over its girth "
              "stopped at body.min_torso_aspect = ", s.fit.min_torso_aspect, " of the template's; region labels may be off "
              "where the legs and neck meet the body (check body/previews)");

  const auto t1 = std::chrono::steady_clock::now();
  const std::vector<fs::path> previews =
      synth::render_region_previews(target, c.scene, preview_views(c.scene, s.preview_views), out.previews());
  const double preview_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();

  json summary{{"model", {{"name", model.name}, {"vertices", model.vertex_count()}, {"joints", model.joint_count()},
                          {"seconds", model_seconds}}},
               {"stages", stages},
               {"chamfer_mean", fit.chamfer_mean},
               {"relative_chamfer", fit.relative_chamfer},
               {"low_confidence", fit.low_confidence},
               {"torso_at_bound", fit.torso_at_bound},
               {"eye_distance", glm::distance(eyes.left, eyes.right)},
               {"eyes_from", eyes.record["source"]},
               {"eye_seconds", eye_seconds},
               {"previews", previews.size()},
               {"preview_seconds", preview_seconds},
               {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()}};
  const json gt = ground_truth_metrics(c, target, fitted_eyes, eyes);
  if (!gt.is_null()) summary["ground_truth"] = gt;
  write_file_atomic(out.metrics(), summary.dump(2) + "\n");
  return summary;
}

const SettingsSchema<BodySettings>& body_settings() {
  using B = BodySettings;
  static const SettingsSchema<B> schema = [] {
    SettingsSchema<B> s("body", [](const std::string& quality) {
      B b;
      if (quality == "draft") {
        b.fit.samples = 5000;
        b.fit.hypothesis_steps = 25;
        b.fit.global_steps = 60, b.fit.pose_steps = 150, b.fit.offset_steps = 60;
      }
      return b;
    });
    s.add("samples", [](B& b) -> auto& { return b.fit.samples; }, 100, 1e6, "points drawn on M_NeuS per step")
        .add("hypothesis_steps", [](B& b) -> auto& { return b.fit.hypothesis_steps; }, 1, 1e5,
             "stage-1 steps per initial placement tried")
        .add("global_steps", [](B& b) -> auto& { return b.fit.global_steps; }, 0, 1e5, "stage 1: rotation, translation, scale")
        .add("pose_steps", [](B& b) -> auto& { return b.fit.pose_steps; }, 0, 1e5, "stage 2: + shape and joint rotations")
        .add("offset_steps", [](B& b) -> auto& { return b.fit.offset_steps; }, 0, 1e5, "stage 3: + per-vertex offsets")
        .add("global_lr", [](B& b) -> auto& { return b.fit.global_lr; }, 1e-6, 1, "Adam rate of the placement")
        .add("pose_lr", [](B& b) -> auto& { return b.fit.pose_lr; }, 1e-6, 1, "Adam rate of the joint rotations")
        .add("shape_lr", [](B& b) -> auto& { return b.fit.shape_lr; }, 1e-6, 1, "Adam rate of the shape coefficients")
        .add("offset_lr", [](B& b) -> auto& { return b.fit.offset_lr; }, 1e-7, 1, "Adam rate of the per-vertex offsets")
        .add("chamfer_weight", [](B& b) -> auto& { return b.fit.weights.chamfer; }, 0, 1e6, "two-way chamfer")
        .add("laplacian_weight", [](B& b) -> auto& { return b.fit.weights.laplacian; }, 0, 1e6,
             "Laplacian smoothness of the offsets (paper 0.01)")
        .add("edge_weight", [](B& b) -> auto& { return b.fit.weights.edge; }, 0, 1e6, "edge term of the offsets (paper 0.8)")
        .add("normal_weight", [](B& b) -> auto& { return b.fit.weights.normal; }, 0, 1e6,
             "normal consistency of the fitted surface (paper 0.02)")
        .add("pose_prior_weight", [](B& b) -> auto& { return b.fit.weights.pose_prior; }, 0, 1e6,
             "sum of squared joint angles")
        .add("joint_limit_weight", [](B& b) -> auto& { return b.fit.weights.joint_limit; }, 0, 1e6,
             "squared excess of a joint angle over max_joint_angle")
        .add("shape_prior_weight", [](B& b) -> auto& { return b.fit.weights.shape_prior; }, 0, 1e6,
             "sum of squared shape coefficients")
        .add("max_joint_angle", [](B& b) -> auto& { return b.fit.max_joint_angle; }, 0.01, 3.2,
             "joint limit in radians")
        .add("min_torso_aspect", [](B& b) -> auto& { return b.fit.min_torso_aspect; }, 0, 1,
             "the torso's length over its girth kept at least this share of the template's (0: unbounded)")
        .add("seed", [](B& b) -> auto& { return b.fit.seed; }, 0, 4294967295.0, "sampling seed")
        .add("preview_views", [](B& b) -> auto& { return b.preview_views; }, 0, 16, "region-coloured preview renders")
        .add("photo_eyes", [](B& b) -> auto& { return b.photo_eyes; }, 0, 1,
             "find the eyes in the photos and triangulate them (else the fitted template's eyes)")
        .text("model", [](B& b) -> auto& { return b.model; }, {},
              "a SMAL-layout .npz (tools/smal_to_npz.py); empty: the built-in quadruped family");
    return s;
  }();
  return schema;
}

}  // namespace nf::pipeline
