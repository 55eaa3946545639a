#include "engine/pipeline/fur_stage.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/core/log.hpp"
#include "engine/core/progress.hpp"
#include "engine/core/random.hpp"
#include "engine/core/stats.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/body/regions.hpp"
#include "engine/defur/vertex_fur.hpp"
#include "engine/fur/baseline_groom.hpp"
#include "engine/fur/fur_model_file.hpp"
#include "engine/fur/fur_resolution.hpp"
#include "engine/fur/fur_view_file.hpp"
#include "engine/fur/body_colors.hpp"
#include "engine/fur/strand_colors.hpp"
#include "engine/fur/strand_shapes.hpp"
#include "engine/fur/ground_truth_inputs.hpp"
#include "engine/gpu/context.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/io/image.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/npz.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/io/view_names.hpp"
#include "engine/io/view_split.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/metrics/color_scores.hpp"
#include "engine/metrics/groom_scores.hpp"
#include "engine/pipeline/body_stage.hpp"
#include "engine/pipeline/checkpoint.hpp"
#include "engine/pipeline/defur_stage.hpp"
#include "engine/pipeline/fur_evaluation.hpp"
#include "engine/pipeline/fur_selection.hpp"
#include "engine/pipeline/frames_stage.hpp"
#include "engine/pipeline/knowledge_stage.hpp"
#include "engine/pipeline/preview_views.hpp"
#include "engine/splat/rasterizer.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr int kStageVersion = 8;  // 2: fur/roots.npz when the groom has roots of its own; 3: selection, length factors; 4: the selection trades held-out orientation against the envelope; 5: strand colours; 6: body colours; 7: strand and body colours in one pass (metrics.json colors.seconds is the pass); 8: the chamfer margin follows the photos' resolution of the fur

}  // namespace

fur::FaceFrames read_face_frames(const fs::path& file, std::size_t faces) {
  fur::FaceFrames f;
  for (auto [name, out] : {std::pair{"tangent", &f.tangent}, {"normal", &f.normal}}) {
    const io::NpyArray a = io::read_npz_array(file, name);
    if (a.shape.size() != 2 || a.shape[0] != faces || a.shape[1] != 3)
      throw InputError(file.string() + ": array '" + name + "' should be " + std::to_string(faces) + " x 3 (one per face of defur/bald.ply); rerun the frames stage");
    out->resize(faces);
    for (std::size_t i = 0; i < faces; ++i) (*out)[i] = glm::vec3(a.values[3 * i], a.values[3 * i + 1], a.values[3 * i + 2]);
  }
  return f;
}

fs::path groom_roots_file(const fs::path& work) {
  const FurOutputs o = fur_outputs(work);
  const json m = io::read_json_file(o.metrics());
  const io::JsonField field = io::JsonField(m, o.metrics().string()).at("roots_file");
  if (!field.value().is_string() || (field.value() != "frames/roots.npz" && field.value() != "fur/roots.npz"))
    field.fail("expected \"frames/roots.npz\" or \"fur/roots.npz\"; rerun the fur stage");
  return work / field.value().get<std::string>();
}

namespace {

// The groom over the photo: orientation as hue (doubled angle, as `nf_gpu orient` draws it) where
// the strands cover the pixel, the photo elsewhere; beside it the Gabor map of the photo.
io::Image preview_image(const fur::FurView& v, const std::vector<float>& image) {
  const std::uint32_t W = v.crop.width, H = v.crop.height;
  const std::uint64_t px = v.pixels();
  io::Image out{2 * W, H, 3, std::vector<float>(std::size_t(2) * px * 3, 0.f)};
  const auto hue = [](double angle, float* rgb) {
    const double h = std::fmod(angle / M_PI, 1.0) * 6.0;
    const double x = 1.0 - std::abs(std::fmod(h, 2.0) - 1.0);
    const double table[6][3] = {{1, x, 0}, {x, 1, 0}, {0, 1, x}, {0, x, 1}, {x, 0, 1}, {1, 0, x}};
    for (int c = 0; c < 3; ++c) rgb[c] = float(table[std::min(5, int(h))][c]);
  };
  for (std::uint32_t y = 0; y < H; ++y)
    for (std::uint32_t x = 0; x < W; ++x) {
      const std::size_t p = std::size_t(y) * W + x;
      float* left = &out.pixels[(std::size_t(y) * 2 * W + x) * 3];
      float* right = &out.pixels[(std::size_t(y) * 2 * W + W + x) * 3];
      float c[3];
      hue(0.5 * std::atan2(double(image[2 * px + p]), double(image[px + p])) + M_PI, c);
      const float a = std::clamp(image[p], 0.f, 1.f);
      for (int ch = 0; ch < 3; ++ch) left[ch] = (1 - a) * v.rgb[3 * p + std::size_t(ch)] + a * c[ch];
      float g[3];
      hue(v.gabor_angle[p], g);
      const float conf = v.gabor_confidence[p];
      for (int ch = 0; ch < 3; ++ch) right[ch] = conf * g[ch] * (v.mask[p] > 0.5f ? 1.f : 0.f);
    }
  return out;
}

// Says in the log how many photo pixels the fur spans and what that does to the image losses
// (fur_resolution.hpp); returns the figures for metrics.json.
json log_fur_resolution(const std::vector<fur::ViewResolution>& views, double resolved_px) {
  if (views.empty()) return {{"fur_pixels_median", 0.0}, {"image_weight_mean", 0.0}, {"views_without_image_losses", 0}};
  std::vector<double> px;
  double weight = 0;
  std::size_t partly = 0, off = 0, unseen = 0;
  for (const fur::ViewResolution& v : views) {
    px.push_back(v.fur_pixels), weight += v.image_weight / double(views.size());
    partly += v.image_weight > 0 && v.image_weight < 1, off += v.image_weight == 0, unseen += v.fur_pixels == 0;
  }
  const double median = nf::median(px);
  char line[400];
  std::snprintf(line, sizeof line, "fur: the fur spans %.1f photo pixels (median over the %zu training views)", median, views.size());
  log::info(line);
  if (off == views.size()) {
    std::snprintf(line, sizeof line,
                  "fur: no photo resolves the fur (%.1f px long; the image losses fade in from %.1f px and weigh fully from %.1f): "
                  "they are off, and the groom follows the knowledge, M_bald and M_NeuS; photos where the fur spans %.1f px or more let them correct it",
                  median, resolved_px / 2, resolved_px, resolved_px);
    log::warn(line);
  } else if (partly + off > 0) {
    std::snprintf(line, sizeof line,
                  "fur: of %zu training views, %zu resolve the fur only partly and %zu not at all (full weight from %.1f px): their "
                  "image losses are weighted down (mean weight %.2f over the views; those of weight 0 are not rendered)",
                  views.size(), partly, off, resolved_px, weight);
    log::warn(line);
  }
  if (unseen) log::warn("fur: ", unseen, " training view(s) see none of the roots (a camera that misses the animal?)");
  return {{"fur_pixels_median", median}, {"image_weight_mean", weight}, {"views_without_image_losses", off}};
}

}  // namespace

FurSettings fur_quality_preset(const std::string& quality) {
  FurSettings s;
  if (quality == "draft") {
    s.training.steps = 300, s.training.strands = 4000, s.training.warm_steps = 50, s.resolution = 256;
    s.training.checkpoint_interval = 100, s.strands = 200000, s.metric_strands = 10000;
  } else if (quality == "paper") {
    s.training.steps = 20000, s.training.strands = 15000, s.training.warm_steps = 200, s.resolution = 0;
    s.training.checkpoint_interval = 500, s.metric_strands = 100000;
  }
  return s;
}

std::vector<fs::path> FurStage::inputs(const StageContext& c) const {
  const DefurOutputs d = defur_outputs(c.work);
  const FramesOutputs f = frames_outputs(c.work);
  const KnowledgeOutputs k = knowledge_outputs(c.work);
  std::vector<fs::path> files{d.bald(), d.vertex_fur(), d.bald_sdf(), f.frames(), f.roots(), k.scale(), k.knowledge(),
                              body_outputs(c.work).outer_regions()};
  std::vector<std::uint32_t> views(c.scene.cameras.size());
  for (std::uint32_t v = 0; v < views.size(); ++v) views[v] = v;
  const std::vector<std::string> names = io::view_file_names(c.scene, views);
  for (std::uint32_t v = 0; v < views.size(); ++v) {
    const io::Camera& cam = c.scene.cameras[v];
    if (!cam.image.empty()) files.push_back(cam.image);
    if (!cam.mask.empty()) files.push_back(cam.mask);
    const fs::path nonbald = d.masks() / (names[v] + ".png");
    if (fs::exists(nonbald)) files.push_back(nonbald);
  }
  if (const auto gt = io::find_ground_truth(c.scene_dir)) {
    for (const fs::path& p : {gt->strands(), gt->outer()})
      if (fs::exists(p)) files.push_back(p);
    if (settings_of(c).truth != "none")
      for (const fs::path& p : {gt->bald(), gt->knowledge(), gt->scene_json()})
        if (fs::exists(p)) files.push_back(p);
    if (settings_of(c).orientation_target == "truth")
      for (const io::Camera& cam : c.scene.cameras)
        if (fs::exists(gt->orientation(cam.name))) files.push_back(gt->orientation(cam.name));
  }
  return files;
}

json FurStage::parameters(const StageContext& c) const {
  return key_of(c, kStageVersion);
}

namespace {

// What the stage reads, once: the earlier stages' results (or the truth swapped in for them).
struct FurInputs {
  geometry::Mesh bald;
  std::optional<geometry::Mesh> envelope;  // M_NeuS (or the true envelope with truth=all)
  defur::VertexFur vertex_fur;
  double cm = 1;
  fur::FurTrainingData data;
  std::optional<fur::GroundTruthInputs> swapped;
  std::unique_ptr<fur::FurPatches> patches;  // with fur.patch: the views' native targets on disk
};

FurInputs read_inputs(StageContext& c, const FurSettings& s) {
  const DefurOutputs d = defur_outputs(c.work);
  FurInputs in;
  in.bald = io::read_mesh(d.bald());
  in.vertex_fur = defur::read_vertex_fur(d.vertex_fur(), in.bald.vertex_count());
  in.cm = read_metric_scale(knowledge_outputs(c.work));
  in.data.roots = fur::read_roots(frames_outputs(c.work).roots());
  in.swapped = swap_in_truth(c.gpu, c.scene_dir, s, in.bald, in.vertex_fur, in.data, in.cm);
  in.data.cm_per_unit = in.cm;
  if (in.data.roots.size() == 0) return in;
  if (s.truth != "all") {
    const knowledge::Knowledge knowledge = knowledge::read_knowledge(knowledge_outputs(c.work).knowledge());
    in.envelope = io::read_mesh(body_outputs(c.work).outer_regions());
    in.data.bald_sdf = defur::read_sdf_file(d.bald_sdf());
    fur::set_surface_inputs(in.data, *in.envelope, [&](std::int32_t r) { return knowledge.grows_fur(body::Region(r)); }, s.training.seed);
  } else {
    in.envelope = in.swapped->outer;
  }
  in.data.fur_area = fur::fur_area(in.bald, in.vertex_fur);
  return in;
}

json write_bald_groom(const FurOutputs& out) {
  log::warn("fur: every region of the knowledge is bald, so there is no fur to grow; writing an empty groom");
  io::write_uniform_hair(out.strands(), 0, fur::kStrandPoints, [](const auto&) {});
  io::write_npz(out.regions(), {{"region", {0}, "<i4", {}}});
  json summary{{"strands", 0}, {"roots_file", "frames/roots.npz"}, {"note", "every region is bald: no strands"}};
  write_file_atomic(out.metrics(), summary.dump(2) + "\n");
  return summary;
}

// Training and held-out cameras that have a photo and a mask, split by io::is_held_out; a scene
// whose every usable camera would be held out trains on them instead.
void split_views(const io::Scene& scene, int hold_out_every, std::vector<std::uint32_t>& train, std::vector<std::uint32_t>& held_out) {
  for (std::uint32_t v = 0; v < scene.cameras.size(); ++v) {
    const io::Camera& cam = scene.cameras[v];
    if (cam.image.empty() || cam.mask.empty()) {
      log::warn("fur: camera '", cam.name, "' has no ", cam.image.empty() ? "photo" : "mask", "; it is not used");
      continue;
    }
    (io::is_held_out(v, hold_out_every) ? held_out : train).push_back(v);
  }
  if (train.empty() && !held_out.empty()) train.swap(held_out);  // a single view trains
}

// The views' targets at the stage's resolution, cropped to the masks, and with fur.patch their
// native targets in a patch store under `scratch` (the stage's resume folder), where the views an
// interrupted run finished are read back from; returns the log's figures.
json make_views(StageContext& c, const FurSettings& s, FurInputs& in, const fs::path& scratch) {
  std::vector<std::uint32_t> train_ids, held_ids;
  split_views(c.scene, s.hold_out_every, train_ids, held_ids);
  std::vector<std::uint32_t> all(c.scene.cameras.size());
  for (std::uint32_t v = 0; v < all.size(); ++v) all[v] = v;
  const std::vector<std::string> names = io::view_file_names(c.scene, all);
  fur::FurViewOptions view_options;
  view_options.max_side = s.resolution, view_options.margin_px = s.margin_px;
  view_options.true_orientation = s.orientation_target == "truth";
  const fs::path masks = defur_outputs(c.work).masks();
  // The native targets stay in `scratch` (the stage's resume folder, which the pipeline removes once
  // the stage is done) with the views' files: a resumed run reads back the views its last run made.
  if (s.patch) {
    in.patches = std::make_unique<fur::FurPatches>(c.gpu, in.bald, scratch / "patches", s.patch, fur::FurPatches::Files::kept);
    in.data.patches = in.patches.get();
  }
  // Held-out views' native targets go to a store of their own: only their fixed patches are cut from
  // it (its files stay for a resumed run, like the training views').
  std::unique_ptr<fur::FurPatches> held_store;
  if (s.patch) held_store = std::make_unique<fur::FurPatches>(c.gpu, in.bald, scratch / "held_out_patches", s.patch, fur::FurPatches::Files::kept);
  const fs::path kept = scratch / "views";
  fs::create_directories(kept);
  std::uint32_t most_scales = 1;
  // Minutes for photos of several megapixels (their Gabor maps at full resolution): a progress line.
  Progress progress("fur views", train_ids.size() + held_ids.size());
  std::size_t prepared = 0, read_back = 0;
  const auto make = [&](const std::vector<std::uint32_t>& ids, std::vector<fur::FurView>& views, fur::FurPatches* store) {
    for (std::uint32_t v : ids) {
      fur::FurViewOptions o = view_options;
      if (store) {
        // The scales the photo's strands need (fur_resolution.hpp), from the fur's length in it.
        fur::FurView probe;
        probe.crop = c.scene.cameras[v], probe.scale = 1;
        // (A true orientation map has one scale: the photo's own.)
        o.gabor_scales = o.true_orientation ? 1
                                            : fur::gabor_scales_for(fur::fur_length_pixels(probe, in.data.roots), s.training.resolved_fur_px, s.gabor_scales);
        most_scales = std::max(most_scales, o.gabor_scales);
      }
      const fs::path file = kept / ("camera_" + std::to_string(v) + ".nfview");
      if (std::optional<fur::StoredFurView> stored = fur::read_fur_view(file, c.scene);
          stored && (!store || (stored->native_crop && store->reopen(v, *stored->native_crop)))) {
        views.push_back(std::move(stored->view));
        ++read_back;
      } else {
        const fs::path nonbald_file = masks / (names[v] + ".png");
        // The defur stage's non-bald masks belong to the pipeline's M_bald, not to the true one.
        const std::optional<io::Image> nonbald =
            s.truth != "all" && fs::exists(nonbald_file) ? std::optional(io::read_image(nonbald_file)) : std::nullopt;
        fur::NativeTargets native;
        views.push_back(fur::make_fur_view(c.gpu, c.scene, v, nonbald ? &*nonbald : nullptr, in.bald, o, store ? &native : nullptr));
        if (store) store->add(v, native);
        fur::write_fur_view(file, views.back(), store ? &native.crop : nullptr);  // after the native targets: it says they are whole
      }
      progress.update(++prepared, "camera " + c.scene.cameras[v].name);
    }
  };
  try {
    make(train_ids, in.data.train, in.patches.get());
    make(held_ids, in.data.held_out, held_store.get());
  } catch (...) {
    progress.stop("stopped");  // not a finished line before the error
    throw;
  }
  progress.finish();
  if (read_back) log::info("fur: ", read_back, " of ", prepared, " views' targets read back from the interrupted run");
  if (held_store)
    for (std::uint32_t h = 0; h < held_store->size(); ++h)
      // Seeded by the camera alone: runs of other seeds are scored on the same patches.
      for (const fur::PatchPlace& p : held_store->places(h, s.held_out_patches, splitmix64(0x5eedull + held_store->camera(h))))
        in.data.held_out_patches.push_back(held_store->cut(h, p));
  std::uint64_t rendered = 0, full = 0;
  double reliability = 0;
  for (const fur::FurView& v : in.data.train) {
    rendered += v.pixels(), full += std::uint64_t(c.scene.cameras[v.camera].width) * c.scene.cameras[v.camera].height;
    reliability += v.orientation_reliability / double(in.data.train.size());
  }
  const std::uint64_t per_view = rendered / std::max<std::size_t>(1, in.data.train.size());
  log::info("fur: the photos' orientation maps are ", 100.0 * reliability, " % reliable on the fur (their coherence above noise)");
  log::info("fur: ", in.data.roots.size(), " roots, ", in.data.train.size(), " training views and ", in.data.held_out.size(),
            " held out; rendering ", per_view, " pixels a view (", full ? 100.0 * double(rendered) / double(full) : 0.0, " % of the photos' pixels)");
  if (in.data.train.empty()) log::warn("fur: no view has a photo and a mask; only the geometric losses will shape the fur");
  json figures{{"train", in.data.train.size()}, {"held_out", in.data.held_out.size()}, {"read_back", read_back}, {"orientation_reliability", reliability},
               {"rendered_pixels_per_view", per_view}, {"rendered_fraction_of_photo", full ? double(rendered) / double(full) : 0.0}};
  if (in.patches) {
    double native = 0;
    for (std::uint32_t v = 0; v < in.patches->size(); ++v) native += in.patches->orientation_reliability(v) / double(in.patches->size());
    log::info("fur: image steps render patches of up to ", s.patch, " px at the photos' resolution; their orientation maps are ", 100.0 * native,
              " % reliable there (up to ", most_scales, " Gabor scale(s)); ", double(in.patches->bytes_on_disk()) / 1e6, " MB of targets on disk");
    figures["patches"] = {{"size", s.patch},
                          {"orientation_reliability", native},
                          {"gabor_scales", most_scales},
                          {"gabor_scale_share", in.patches->scale_share()},
                          {"held_out_patches", in.data.held_out_patches.size()},
                          {"bytes_on_disk", in.patches->bytes_on_disk()}};
  }
  return figures;
}

// The steps to train: all of them, or only the warm-up where no training photo resolves the fur
// (select=auto): without a photo the later steps have only the chamfer and curvature, which pull
// the strands off the warm start with nothing to say where they should go.
std::uint32_t steps_to_train(const FurSettings& s, const fur::FurTrainer& trainer, const fur::FurTrainingData& data) {
  if (s.select == "auto" && !data.train.empty() && !trainer.any_view_resolves_fur() && s.training.steps > s.training.warm_steps) {
    log::warn("fur: no training photo resolves the fur, so training stops after the ", s.training.warm_steps,
              " warm-up steps (fur.select=trained runs all ", s.training.steps, ")");
    return s.training.warm_steps;
  }
  return s.training.steps;
}

// Trains (resuming from `checkpoint` when it fits), with the curve; Interrupted saves a checkpoint.
// Returns how well the photos resolve the fur (log_fur_resolution), said before training.
json train(StageContext& c, const FurSettings& s, const FurInputs& in, std::unique_ptr<fur::StrandPrior>& prior,
           std::unique_ptr<fur::FurTrainer>& trainer, FurCurve& curve, const fs::path& checkpoint) {
  auto make_trainer = [&] { return std::make_unique<fur::FurTrainer>(c.gpu, in.data, *prior, s.field, s.training); };
  trainer = make_trainer();
  const json resolution = log_fur_resolution(trainer->view_resolution(), s.training.resolved_fur_px);
  const bool resumed = resume_or_discard("fur", checkpoint, [&] { return trainer->load_checkpoint(checkpoint); },
                                         [&] {
                                           prior = fur::shipped_strand_prior(c.gpu);
                                           trainer = make_trainer();
                                         });
  if (resumed) log::info("fur: resuming from ", checkpoint.string(), " at step ", trainer->step());
  curve.start(*trainer, in.data, c.scene, resumed);
  const std::uint32_t steps = steps_to_train(s, *trainer, in.data);
  log::info("fur: ", steps, " steps of ", std::min<std::size_t>(s.training.strands, in.data.roots.size()), " strands (", s.training.warm_steps,
            " warm-up), strand width ", trainer->strand_width(trainer->batch()) * in.cm * 10.0, " mm");
  Progress progress("fur", steps);
  trainer->train(steps, checkpoint, [&](const fur::FurStepReport& r) {
    char status[200];
    if (r.warm)
      std::snprintf(status, sizeof status, "warm-up: direction %.4f penetration %.2e", r.direction, r.penetration);
    else
      std::snprintf(status, sizeof status, "loss %.4f sil %.3f orient %.4f chamfer %.2e length x%.2f", r.loss, r.silhouette, r.orientation,
                    r.chamfer, r.length_factor_mean);
    progress.update(r.step, status);
    if (!interrupted()) curve.after_step(*trainer, in.data, c.scene, r.seconds);
    return !interrupted();
  });
  if (interrupted()) {
    trainer->save_checkpoint(checkpoint);
    progress.stop("stopped");
    throw Interrupted("fur: stopped at step " + std::to_string(trainer->step()) + " of " + std::to_string(steps) + "; checkpoint saved in " +
                      checkpoint.string());
  }
  progress.finish();
  return resolution;
}

// Which groom to keep (fur_selection.hpp): the 0-step groom, the warm-up's, the trained one, each
// later one only where it beats the one kept so far, by a margin at M_NeuS that follows how well the
// training photos resolve the fur (`image_weight`). Leaves the trainer's field at the choice.
json select_groom(StageContext& c, const FurSettings& s, const FurInputs& in, fur::FurTrainer& trainer, const FurGroundTruth& gt,
                  double image_weight) {
  const fur::FurFieldState* warm = trainer.warm_state();
  if (s.select == "trained") return {{"kept", "trained"}, {"reason", "fur.select=trained"}};
  if (s.select == "warm") {
    if (!warm) return {{"kept", "trained"}, {"reason", "fur.select=warm, but training ended before the warm-up did"}};
    trainer.set_state(*warm);
    return {{"kept", "warm-up"}, {"reason", "fur.select=warm"}};
  }
  // Each candidate's signals and, on synth scenes, its scores against the truth (for the docs).
  const auto measure = [&](const fur::FurFieldState& state, json& record) {
    trainer.set_state(state);
    metrics::StrandSample grown;
    const GroomSignals g = measure_groom(trainer, in.data, c.scene, *in.envelope, s, in.cm, &grown);
    record = to_json(g);
    if (gt.sample) record["fscore"] = metrics::groom_scores(grown, {gt.truth().strands, nullptr}, gt.scale_or(in.cm))["fscore"];
    return g;
  };
  const fur::FurFieldState trained = trainer.state();
  std::vector<std::pair<const char*, const fur::FurFieldState*>> candidates{{"0-step", &trainer.start_state()}};
  if (warm && warm->step > 0) candidates.push_back({"warm-up", warm});
  if (trained.step > (warm ? warm->step : 0)) candidates.push_back({"trained", &trained});
  json record;
  const fur::FurFieldState* kept = nullptr;
  const char* kept_name = "";
  GroomSignals kept_signals;
  GroomChoiceTolerances tolerances;
  tolerances.image_weight = image_weight;
  std::string reason;
  for (const auto& [name, state] : candidates) {
    const GroomSignals g = measure(*state, record[name]);
    if (!kept) {
      kept = state, kept_name = name, kept_signals = g;
      continue;
    }
    const GroomChoice choice = choose_groom(kept_signals, g, tolerances);
    record[name]["against"] = kept_name, record[name]["kept"] = choice.trained, record[name]["reason"] = choice.reason;
    if (choice.trained) kept = state, kept_name = name, kept_signals = g, reason = choice.reason;
  }
  trainer.set_state(*kept);
  record["kept"] = kept_name;
  record["envelope_allowed"] = tolerances.envelope_allowed(!in.data.held_out.empty());
  record["reason"] = reason.empty() ? "no later groom gained on the held-out views or M_NeuS" : reason;
  log::info("fur: keeping the ", kept_name, " groom: ", record["reason"].get<std::string>());
  return record;
}

// The kept groom's strands at `strands` roots, streamed to strands.hair with their regions; every
// k-th strand kept for the scores (the roots are stratified over the fur, so a uniform subset).
struct InferredGroom {
  const fur::Roots* roots = nullptr;
  fur::Roots drawn;  // when the count differs from the training roots
  bool own_roots = false;
  std::vector<std::uint32_t> sample_ids;
  std::vector<float> sample_xyz;
  fur::StrandControls controls;  // with fur.color_controls: every strand's points where its colours are taken
};
void infer_groom(StageContext& c, const FurSettings& s, const FurInputs& in, fur::FurTrainer& trainer, const FurOutputs& out,
                 const std::function<void(const char*)>& stop_if_interrupted, InferredGroom& g) {
  g.roots = &in.data.roots;
  if (s.strands != in.data.roots.size()) {
    const fur::FaceFrames frames = in.swapped ? in.swapped->frames : read_face_frames(frames_outputs(c.work).frames(), in.bald.triangle_count());
    g.drawn = fur::sample_roots(in.bald, frames, in.vertex_fur, s.strands, s.training.seed + 11);
    g.roots = &g.drawn;
  }
  // What edit and export need to know where each strand grows, when it is not frames/roots.npz.
  g.own_roots = g.roots != &in.data.roots || in.swapped.has_value();
  if (g.own_roots) fur::write_roots(out.roots(), *g.roots);
  g.controls.controls = s.color_controls;
  const std::uint32_t n = std::uint32_t(g.roots->size());
  std::vector<std::uint32_t> ids(n);
  for (std::uint32_t i = 0; i < n; ++i) ids[i] = i;
  const std::uint32_t every = std::max<std::uint32_t>(1, n / std::max<std::uint32_t>(1, s.metric_strands));
  io::write_uniform_hair(out.strands(), n, fur::kStrandPoints, [&](const auto& write) {
    trainer.field().infer(*g.roots, ids, 65536, [&](std::size_t first, std::uint32_t count, const std::vector<float>& points, const std::vector<float>&) {
      stop_if_interrupted("inference");  // the partial file is removed
      write(std::span<const float>(points));
      if (g.controls.controls) g.controls.append(std::span<const float>(points).first(std::size_t(count) * fur::kStrandPoints * 3), fur::kStrandPoints);
      for (std::uint32_t k = 0; k < count; ++k)
        if ((first + k) % every == 0) {
          g.sample_ids.push_back(std::uint32_t(first + k));
          g.sample_xyz.insert(g.sample_xyz.end(), points.begin() + std::ptrdiff_t(std::size_t(k) * fur::kStrandPoints * 3),
                              points.begin() + std::ptrdiff_t(std::size_t(k + 1) * fur::kStrandPoints * 3));
        }
    });
  });
  io::NpyWrite regions{"region", {n}, "<i4", {}};
  regions.values.reserve(n);
  for (std::uint32_t i = 0; i < n; ++i) regions.values.push_back(g.roots->region[i]);
  io::write_npz(out.regions(), {regions});
}

// Every strand's colours from the photos (fur.color_controls), to colors.npz; on synth scenes whose
// true strands carry colours, their error against those. Returns metrics.json's "colors".
json color_groom(StageContext& c, const FurSettings& s, const FurInputs& in, const InferredGroom& g, const FurOutputs& out,
                 const FurGroundTruth& gt) {
  if (!s.color_controls || g.controls.strands == 0) return json{{"controls", 0}};
  std::vector<std::uint32_t> views;
  for (const std::vector<fur::FurView>* list : {&in.data.train, &in.data.held_out})
    for (const fur::FurView& v : *list) views.push_back(v.camera);
  std::sort(views.begin(), views.end());
  if (views.empty() || !in.envelope) {
    log::warn("fur: no photo to take the strands' colours from; the groom has none");
    return json{{"controls", 0}, {"reason", "no view with a photo and a mask"}};
  }
  fur::StrandColorOptions o;
  o.controls = s.color_controls, o.hidden_depth = s.color_hidden_depth;
  // The body's colours (the export's body material) in the same pass over the photos, on the
  // M_bald the export reads: defur's, also when fur.truth=all trained on the true body.
  const Stopwatch t_body_points;
  const geometry::Mesh export_body = in.swapped ? io::read_mesh(defur_outputs(c.work).bald()) : geometry::Mesh{};
  const geometry::Mesh& bald = in.swapped ? export_body : in.bald;
  const fur::StrandControls body_points = fur::body_color_points(bald, *in.envelope);
  const double body_points_seconds = t_body_points.seconds();
  const std::vector<fur::ControlSet> sets{{&g.controls, o}, {&body_points, fur::body_color_options(o)}};
  const std::vector<fur::StrandColors> made = fur::color_control_sets(c.gpu, c.scene, views, *in.envelope, sets);
  const fur::StrandColors& colors = made[0];
  const fur::StrandColors& body = made[1];
  fur::write_strand_colors(out.colors(), colors);
  fur::write_strand_colors(out.body_colors(), body);
  json report = colors.report;
  report["body"] = body.report;
  report["body"]["vertices"] = bald.vertex_count();
  report["body"]["points_seconds"] = body_points_seconds;  // finding each vertex's point on M_NeuS
  log::info("fur: strand and body colours from ", views.size(), " photos in ", report["seconds"].get<double>(), " s; ",
            100.0 * report["strands_seen"].get<double>(), " % of the strands seen, the rest filled from their neighbours; ",
            100.0 * body.report["strands_seen"].get<double>(), " % of the body's ", bald.vertex_count(), " vertices");
  if (gt.colors) {
    const metrics::GroomColors groom{g.controls.roots, colors.seen, [&](std::uint64_t i, float t) { return colors.at(i, t); }, s.color_controls};
    report["ground_truth"] = metrics::color_scores(groom, *gt.colors, s.metric_strands);
    const json& e = report["ground_truth"];
    const auto mean = [](const json& summary) { return summary.value("count", 0) > 0 ? std::to_string(summary["mean"].get<double>()) : std::string("n/a"); };
    log::info("fur: strand colours against the truth: Delta E ", mean(e["delta_e_seen"]), " seen, ", mean(e["delta_e_unseen"]), " unseen");
  }
  return report;
}

// The groom over the held-out views (else the first training views).
json write_previews(StageContext& c, const FurSettings& s, const FurInputs& in, fur::FurTrainer& trainer, const FurOutputs& out,
                    const std::vector<std::vector<float>>& held_images) {
  json previews = json::array();
  if (s.preview_views <= 0) return previews;
  std::vector<std::uint32_t> all(c.scene.cameras.size());
  for (std::uint32_t v = 0; v < all.size(); ++v) all[v] = v;
  const std::vector<std::string> names = io::view_file_names(c.scene, all);
  const std::uint32_t scored = s.score_strands ? s.score_strands : s.training.strands;
  fs::create_directories(out.previews());
  const std::vector<fur::FurView>& source = in.data.held_out.empty() ? in.data.train : in.data.held_out;
  for (std::size_t i = 0; i < source.size() && previews.size() < std::size_t(s.preview_views); ++i) {
    const std::vector<float> image =
        i < held_images.size() && !in.data.held_out.empty() ? held_images[i] : trainer.render(source[i], scored, s.training.seed + 7);
    const fs::path file = out.previews() / (names[source[i].camera] + ".png");
    io::write_png(file, preview_image(source[i], image));
    previews.push_back(file.filename().string());
  }
  return previews;
}

// A step's batch and the held-out scoring each render their strands into one view at once: a count
// the device cannot rasterise fails here, naming the setting, not at the first render after the
// inputs are read (or after the whole training, for the scoring).
void check_strands_per_view(const gpu::Context& gpu, const FurSettings& s) {
  const std::uint64_t most = splat::max_segments_per_view(gpu) / fur::kStrandSegments;
  for (const auto& [name, strands] : {std::pair<const char*, std::uint32_t>{"batch", s.training.strands}, {"score_strands", s.score_strands}})
    if (strands > most)
      throw UsageError("--set fur." + std::string(name) + "=" + std::to_string(strands) + ": this device renders at most " + std::to_string(most) +
                       " strands into one view (" + std::to_string(fur::kStrandSegments) + " segments each); use fewer");
}

}  // namespace

json FurStage::run(StageContext& c, const fs::path& out_dir, const fs::path& resume) {
  const FurSettings s = settings_of(c);
  check_strands_per_view(c.gpu, s);
  const FurOutputs out{out_dir};
  const Stopwatch t_all;
  json seconds = json::object();
  Stopwatch t;

  FurInputs in = read_inputs(c, s);
  write_file_atomic(out.scale(), json{{"cm_per_unit", in.cm}, {"source", in.swapped ? "gt/scene.json" : "knowledge/scale.json"}}.dump(2) + "\n");
  if (in.data.roots.size() == 0) return write_bald_groom(out);
  seconds["read"] = t.seconds();

  t.restart();
  json views = make_views(c, s, in, resume);
  seconds["views"] = t.seconds();
  const std::uint32_t scored = s.score_strands ? s.score_strands : s.training.strands;
  const FurGroundTruth gt = read_fur_ground_truth(c.scene_dir, s, std::min<std::uint32_t>(scored, std::uint32_t(in.data.roots.size())), in.cm);

  t.restart();
  std::unique_ptr<fur::StrandPrior> prior = fur::shipped_strand_prior(c.gpu);
  std::unique_ptr<fur::FurTrainer> trainer;
  const fs::path checkpoint = resume / "checkpoint.nfwt";
  FurCurve curve(s, resume / "curve.jsonl", gt, gt.scale_or(in.cm));
  const json resolution = train(c, s, in, prior, trainer, curve, checkpoint);
  curve.finish(*trainer, in.data, c.scene, out.curve());
  seconds["train"] = t.seconds();
  for (const char* key : {"fur_pixels_median", "image_weight_mean", "views_without_image_losses"}) views[key] = resolution[key];
  // After training, Ctrl-C or a kill stops at the next chunk of work with the trained state saved:
  // the same command then resumes at the last step and only redoes what follows.
  const auto stop_if_interrupted = [&](const char* during) {
    if (!interrupted()) return;
    trainer->save_checkpoint(checkpoint);
    throw Interrupted(std::string("fur: stopped during ") + during + " after " + std::to_string(trainer->step()) +
                      " steps; checkpoint saved in " + checkpoint.string());
  };
  std::string loss_curve;
  for (const fur::FurStepReport& r : trainer->history()) loss_curve += fur::to_json(r).dump() + "\n";
  write_file_atomic(out.training(), loss_curve);

  t.restart();
  const json selection = select_groom(c, s, in, *trainer, gt, resolution["image_weight_mean"].get<double>());
  seconds["selection"] = t.seconds();
  stop_if_interrupted("the selection");
  fur::save_fur_model(out.model(), trainer->field(), *prior, trainer->step(), s.training.train_decoder);

  // Held-out views: the kept groom, the baseline groom on the same roots, the true groom (synth).
  t.restart();
  std::vector<std::vector<float>> held_images;
  const auto stop_if_scoring_interrupted = [&] { stop_if_interrupted("scoring"); };
  // The previews reuse the held-out renderings when these are the whole views (not patches).
  const std::vector<fur::FurView>& held_views = in.data.scored_views();
  const HeldOutScores held = score_field_held_out(*trainer, held_views, c.scene, scored, s.training.seed + 7,
                                                  in.data.held_out_patches.empty() ? &held_images : nullptr, stop_if_scoring_interrupted);
  json held_json = held_out_json(held);
  held_json["views"] = held.views;
  if (!in.data.held_out.empty()) {
    const std::vector<std::uint32_t> scored_ids = fur::sample_indices(in.data.roots.size(), scored, s.training.seed + 7);
    const io::StrandSet held_baseline = fur::baseline_groom(in.data.roots, scored_ids, s.training.lying_angle_deg, fur::kStrandPoints);
    held_json["baseline"] = held_out_json(score_strands_held_out(*trainer, held_views, c.scene, held_baseline.points, stop_if_scoring_interrupted));
    if (gt.rendered && gt.rendered->strands > 0)
      held_json["truth"] = held_out_json(score_strands_held_out(*trainer, held_views, c.scene, gt.rendered->xyz, stop_if_scoring_interrupted));
    log::info("fur: held-out orientation error ", held.orientation_error_deg, " deg (baseline ", held_json["baseline"]["orientation_error_deg"].get<double>(),
              held_json.contains("truth") ? ", true groom " + std::to_string(held_json["truth"]["orientation_error_deg"].get<double>()) : std::string(), ")");
  }
  seconds["held_out"] = t.seconds();

  t.restart();
  InferredGroom groom;
  infer_groom(c, s, in, *trainer, out, stop_if_interrupted, groom);
  const std::uint32_t n = std::uint32_t(groom.roots->size());
  seconds["inference"] = t.seconds();
  log::info("fur: ", n, " strands inferred and written in ", seconds["inference"].get<double>(), " s");
  stop_if_interrupted("the colours");
  t.restart();
  const json colors = color_groom(c, s, in, groom, out, gt);
  seconds["colors"] = t.seconds();

  // Scores: the groom and the baseline groom (straight, lifted, on the same roots).
  stop_if_interrupted("the scores");
  t.restart();
  const io::StrandSet groom_strands = io::StrandSet::uniform(std::uint32_t(groom.sample_ids.size()), fur::kStrandPoints, std::move(groom.sample_xyz));
  const io::StrandSet baseline = fur::baseline_groom(*groom.roots, groom.sample_ids, s.training.lying_angle_deg);
  const json groom_scores = metrics::groom_scores(metrics::sample_strands(groom_strands, s.metric_strands, s.metric_points, 1), gt.truth(), gt.scale_or(in.cm));
  const json baseline_scores = metrics::groom_scores(metrics::sample_strands(baseline, s.metric_strands, s.metric_points, 1), gt.truth(), gt.scale_or(in.cm));
  seconds["metrics"] = t.seconds();
  if (groom_scores.contains("fscore"))
    log::info("fur: F-score at (2 cm, 20 deg) ", groom_scores["fscore"].value("2cm_20deg", 0.0), " (baseline ",
              baseline_scores["fscore"].value("2cm_20deg", 0.0), "); at (2 mm, 20 deg) ", groom_scores["fscore"].value("2mm_20deg", 0.0),
              " (baseline ", baseline_scores["fscore"].value("2mm_20deg", 0.0), ")");

  t.restart();
  const json previews = write_previews(c, s, in, *trainer, out, held_images);
  seconds["previews"] = t.seconds();

  const fur::FurStepReport last = trainer->last_report();
  json summary{{"strands", n},
               {"roots_file", groom.own_roots ? "fur/roots.npz" : "frames/roots.npz"},
               {"steps", trainer->step()},
               {"training_strands_per_step", std::min<std::size_t>(s.training.strands, in.data.roots.size())},
               {"strand_width_mm", trainer->strand_width(trainer->batch()) * in.cm * 10.0},
               {"skipped_steps", last.skipped_steps},
               {"final", fur::to_json(last)},
               {"views", views},
               {"selection", selection},
               {"lengths", fur::length_factors_json(trainer->field().length_factors(), in.data.roots, in.cm,
                                                    [](std::int32_t r) { return body::region_name(r); })},
               {"held_out", held_json},
               {"colors", colors},
               {"groom", groom_scores},
               {"baseline", baseline_scores},
               {"previews", previews},
               {"seconds", seconds},
               {"seconds_per_step", trainer->step() ? last.seconds / trainer->step() : 0.0},
               {"peak_device_bytes", c.gpu.peak_allocated_bytes()}};
  if (!gt.info.is_null()) summary["ground_truth"] = gt.info;
  if (in.swapped) summary["truth"] = s.truth;
  if (curve.enabled()) summary["curve"] = curve.points();
  summary["seconds_total"] = t_all.seconds();
  write_file_atomic(out.metrics(), summary.dump(2) + "\n");
  return summary;
}

const SettingsSchema<FurSettings>& fur_settings() {
  using F = FurSettings;
  static const SettingsSchema<F> schema = [] {
    SettingsSchema<F> s("fur", fur_quality_preset);
    s.add("steps", [](F& f) -> auto& { return f.training.steps; }, 0, 1e8, "optimisation steps (warm-up included)")
        .add("batch", [](F& f) -> auto& { return f.training.strands; }, 1, 1e7, "strands (random roots) per step")
        .add("warm_steps", [](F& f) -> auto& { return f.training.warm_steps; }, 0, 1e8,
             "first steps with the geometric losses only (growth direction, penetration)")
        .add("warm_start", [](F& f) -> auto& { return f.training.warm_start; }, 0, 1,
             "start the field at the straight strand lifted by lying_angle_deg (else: random weights)")
        .add("lying_angle_deg", [](F& f) -> auto& { return f.training.lying_angle_deg; }, 0, 90,
             "the warm start's and the baseline groom's angle between strand and skin")
        .add("lr", [](F& f) -> auto& { return f.training.lr; }, 1e-7, 1, "AdamW learning rate, cosine decay to lr_floor x lr")
        .add("lr_floor", [](F& f) -> auto& { return f.training.lr_floor; }, 0, 1, "the last step's share of lr")
        .add("weight_decay", [](F& f) -> auto& { return f.training.weight_decay; }, 0, 1, "AdamW weight decay")
        .add("image_ramp_steps", [](F& f) -> auto& { return f.training.image_ramp_steps; }, 0, 1e8,
             "steps over which the learning rate ramps up when the image losses start (0: none)")
        .add("resolved_fur_px", [](F& f) -> auto& { return f.training.resolved_fur_px; }, 0, 1e6,
             "fur length in photo pixels from which a view's image losses weigh fully; none at half of it (0: always fully)")
        .add("silhouette_weight", [](F& f) -> auto& { return f.training.weights.silhouette; }, 0, 1e9, "silhouette L1 (0: off)")
        .add("orientation_weight", [](F& f) -> auto& { return f.training.weights.orientation; }, 0, 1e9,
             "orientation against the Gabor maps with rendered confidence (0: off)")
        .add("direction_weight", [](F& f) -> auto& { return f.training.weights.direction; }, 0, 1e9,
             "growth direction against the knowledge (0: off)")
        .add("chamfer_weight", [](F& f) -> auto& { return f.training.weights.chamfer; }, 0, 1e9,
             "one-way chamfer M_NeuS -> strands, in the unit-sphere normalisation (0: off)")
        .add("penetration_weight", [](F& f) -> auto& { return f.training.weights.penetration; }, 0, 1e9,
             "penetration into M_bald, in the unit-sphere normalisation (0: off)")
        .add("envelope_weight", [](F& f) -> auto& { return f.training.weights.envelope; }, 0, 1e9,
             "strand points beyond M_NeuS, in the unit-sphere normalisation (0: off): the counterpart of the chamfer's pull outwards")
        .add("curvature_weight", [](F& f) -> auto& { return f.training.weights.curvature; }, 0, 1e9, "curvature consistency (0: off)")
        .add("chamfer_queries", [](F& f) -> auto& { return f.training.chamfer_queries; }, 0, 60000, "points of M_NeuS per step")
        .add("strand_width", [](F& f) -> auto& { return f.training.strand_width; }, 0, 1,
             "splat sigma across a strand in units of the scene radius (0: from the data, see coverage)")
        .add("coverage", [](F& f) -> auto& { return f.training.coverage; }, 1e-3, 1e3,
             "with strand_width 0: how many times a step's strands cover the fur (sets their width)")
        .add("train_decoder", [](F& f) -> auto& { return f.training.train_decoder; }, 0, 1, "fine-tune the strand prior's decoder too")
        .add("resolution", [](F& f) -> auto& { return f.resolution; }, 0, 65536, "longer side of the rendered views in pixels (0: the photos')")
        .add("margin_px", [](F& f) -> auto& { return f.margin_px; }, 0, 4096, "pixels rendered around each view's mask box")
        .add("patch", [](F& f) -> auto& { return f.patch; }, 0, 8192,
             "side in pixels of the window of a photo each image step renders at the photo's own resolution (the whole view when smaller; 0: whole views at fur.resolution)")
        .add("gabor_scales", [](F& f) -> auto& { return f.gabor_scales; }, 1, 4,
             "with patches: at most this many Gabor maps, of the photo and its halvings (each pixel takes the most reliable; a halving only where the fur spans 2 x resolved_fur_px in it)")
        .add("held_out_patches", [](F& f) -> auto& { return f.held_out_patches; }, 1, 64, "with patches: fixed patches of each held-out view that score the groom")
        .add("hold_out_every", [](F& f) -> auto& { return f.hold_out_every; }, 0, 1000, "every k-th camera is held out for scoring (0 or 1: none)")
        .add("strands", [](F& f) -> auto& { return f.strands; }, 0, 4e7, "strands inferred into strands.hair")
        .add("metric_strands", [](F& f) -> auto& { return f.metric_strands; }, 1, 1e7, "strands the metrics compare")
        .add("metric_points", [](F& f) -> auto& { return f.metric_points; }, 2, 1000, "points per strand the metrics compare")
        .add("score_strands", [](F& f) -> auto& { return f.score_strands; }, 0, 1e7,
             "strands rendered into the held-out views to score a groom: the selection, the curve, metrics' held_out (0: the batch)")
        .add("preview_views", [](F& f) -> auto& { return f.preview_views; }, 0, 100, "previews written")
        .add("color_controls", [](F& f) -> auto& { return f.color_controls; }, 0, 16,
             "colours along each strand taken from the photos, the last at the tip (0: no colours)")
        .add("color_hidden_depth", [](F& f) -> auto& { return f.color_hidden_depth; }, 0, 10,
             "a strand's point deeper behind M_NeuS than this share of the strand's length takes no colour from a photo (the fur in front hides it)")
        .add("checkpoint_interval", [](F& f) -> auto& { return f.training.checkpoint_interval; }, 0, 1e8,
             "steps between checkpoints (0: none; Ctrl-C always saves one)")
        .add("seed", [](F& f) -> auto& { return f.training.seed; }, 0, 4294967295.0, "random seed (initialisation, roots, views)")
        .add("curve_seconds", [](F& f) -> auto& { return f.curve_seconds; }, 0, 1e6,
             "training seconds between two points of curve.jsonl: held-out and ground-truth scores while it trains (0: none)")
        .add("length_lr", [](F& f) -> auto& { return f.training.length_lr; }, 0, 1,
             "Adam learning rate of the per-region length factors learned after the warm-up (0: the knowledge's lengths)")
        .add("length_min", [](F& f) -> auto& { return f.training.length_bounds.lo; }, 0.01, 1, "the smallest length factor")
        .add("length_max", [](F& f) -> auto& { return f.training.length_bounds.hi; }, 1, 100, "the largest length factor")
        .text("select", [](F& f) -> auto& { return f.select; }, {"auto", "trained", "warm"},
              "the groom kept: auto (0-step, warm-up or trained, a later one where the held-out views and M_NeuS say it helped), trained, or warm (the warm-up's)")
        .text("truth", [](F& f) -> auto& { return f.truth; }, {"none", "knowledge", "all"},
              "synth scenes: train on the true knowledge (knowledge) or the true bald body, knowledge and roots (all), to measure what the earlier stages' errors cost")
        .text("orientation_target", [](F& f) -> auto& { return f.orientation_target; }, {"gabor", "truth"},
              "what the orientation loss and the held-out scores compare against: the photos' Gabor maps, or (synth scenes made with --true-orientation) the strands' true orientation, to measure what a perfect orientation map would buy")
        .check([](const F& f) { f.training.validate(); });
    return s;
  }();
  return schema;
}

}  // namespace nf::pipeline
