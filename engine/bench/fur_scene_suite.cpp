#include "engine/bench/fur_scene_suite.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/bench/record.hpp"
#include "engine/bench/scratch_folder.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/text.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/pipeline/fur_stage.hpp"
#include "engine/pipeline/stages.hpp"
#include "engine/synth/synth_scene.hpp"
#include "engine/synth/world_frame.hpp"

namespace nf::bench {
namespace fs = std::filesystem;
namespace {

std::vector<std::string> env_list(const char* name, std::vector<std::string> fallback) {
  const char* value = std::getenv(name);
  if (!value) return fallback;
  std::vector<std::string> out;
  std::istringstream in(value);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty() && item != "none") out.push_back(item);
  return out;
}

// The knowledge a user could have been given wrong: the scene's true knowledge with every
// region's growth direction turned by kTurnDegrees about the animal's left-right axis (hair that
// lies towards the tail then rises off the back). What the photos buy when the knowledge is wrong.
constexpr float kTurnDegrees = 60;
fs::path turned_knowledge_file(const fs::path& scene) { return scene.parent_path() / (scene.filename().string() + "-knowledge-turned.json"); }

void write_turned_knowledge(const fs::path& scene) {
  knowledge::Knowledge k = knowledge::read_knowledge(scene / "gt" / "knowledge.json");
  const glm::mat3 turn(glm::rotate(glm::mat4(1.f), glm::radians(kTurnDegrees), glm::vec3(1, 0, 0)));
  for (auto& region : k.regions)
    if (region && glm::length(region->direction) > 0) region->direction = glm::normalize(turn * region->direction);  // [0,0,0]: none
  knowledge::write_knowledge(turned_knowledge_file(scene), k);
}

// The settings of a variant of the run ("" : none) after the knowledge preset's. Variants join
// with '+' (`truth_envelope+truth_knowledge_file`: both swaps). Most change the fur stage only;
// `truth_knowledge_file` replaces the knowledge preset with the scene's gt/knowledge.json from the
// knowledge stage on, so the defur stage removes the fur's true thickness (the fur stage's
// `truth=knowledge` comes after defur and keeps the preset's), and `truth_envelope` replaces the
// draft NeuS with gt/outer.ply (neus.mesh), so every stage after it reruns on the true envelope.
std::vector<std::string> variant_settings(const std::string& variant, const fs::path& scene) {
  if (variant.empty()) return {};
  if (const std::size_t plus = variant.find('+'); plus != std::string::npos) {
    if (plus == 0 || plus + 1 == variant.size())
      throw UsageError("NF_BENCH_FUR_VARIANTS: '" + variant + "' joins an empty variant (write a+b)");
    std::vector<std::string> both = variant_settings(variant.substr(0, plus), scene);
    for (std::string& s : variant_settings(variant.substr(plus + 1), scene)) both.push_back(std::move(s));
    return both;
  }
  if (variant == "warm_off") return {"fur.warm_start=0", "fur.warm_steps=0"};
  if (variant == "truth_knowledge") return {"fur.truth=knowledge"};
  if (variant == "truth_knowledge_file") return {"knowledge.file=" + (scene / "gt" / "knowledge.json").string()};
  if (variant == "truth_envelope") return {"neus.mesh=" + (scene / "gt" / "outer.ply").string()};
  if (variant == "truth_all") return {"fur.truth=all"};
  if (variant == "select_trained") return {"fur.select=trained"};  // the selection off
  if (variant == "lengths") return {"fur.length_lr=0.01"};         // lengths learned from the photos
  if (variant == "patches") return {"fur.patch=384"};               // native-resolution patches (off by default)
  if (variant == "true_orientation") return {"fur.orientation_target=truth"};  // a perfect orientation map
  if (variant == "knowledge_turned") return {"knowledge.file=" + turned_knowledge_file(scene).string()};
  for (const char* loss : {"silhouette", "orientation", "direction", "chamfer", "penetration", "curvature", "envelope"})
    if (variant == std::string("no_") + loss) return {std::string("fur.") + loss + "_weight=0"};
  throw UsageError("NF_BENCH_FUR_VARIANTS: unknown variant '" + variant +
                   "' (warm_off, truth_knowledge, truth_knowledge_file, truth_envelope, truth_all, select_trained, lengths, patches, true_orientation, "
                   "knowledge_turned, no_silhouette, no_orientation, "
                   "no_direction, no_chamfer, no_penetration, no_curvature, no_envelope; join with '+')");
}

bool sets_stage(const std::vector<std::string>& settings, const std::string& stage) {
  for (const std::string& s : settings)
    if (s.rfind(stage + ".", 0) == 0) return true;
  return false;
}

json read_json(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": missing");
  return json::parse(in);
}

// A groom's scores as the record keeps them: F-scores, tips to the envelope.
json groom_summary(const json& scores) {
  json s = json::object();
  if (scores.contains("fscore")) s["fscore"] = scores["fscore"];
  if (scores.contains("tips_to_outer")) s["tips_to_outer"] = scores["tips_to_outer"];
  return s;
}

// The strands' colours as the record keeps them: the share seen, the seconds, and on synth scenes
// the mean Delta E against the true colours, seen and filled (issue 46's targets: 8 and 15).
json colors_summary(const json& colors) {
  json s{{"strands_seen", colors.value("strands_seen", 0.0)}, {"seconds", colors.value("seconds", 0.0)}};
  if (colors.contains("ground_truth"))
    for (const char* key : {"delta_e_seen", "delta_e_unseen"})
      if (colors["ground_truth"][key].value("count", 0) > 0) s[key] = colors["ground_truth"][key]["mean"];
  return s;
}

// The held-out views' scores of the groom, with the baseline groom's and the true groom's (the
// truth's own score against the photos' Gabor maps) where the stage rendered them.
json held_out_summary(json held) {
  held.erase("views");  // per view: metrics.json keeps them
  return held;
}

}  // namespace

json run_fur_scene_suite(gpu::Context& ctx, const Options& options) {
  // NF_BENCH_FUR_DIR keeps the scenes and WORK folders: a second run reuses the earlier stages.
  const ScratchFolder scratch("NF_BENCH_FUR_DIR", "nf-bench-fur-");
  const fs::path& root = scratch.path();
  const std::vector<std::string> animals = env_list("NF_BENCH_FUR_ANIMALS", options.quick ? std::vector<std::string>{"cat"} : std::vector<std::string>{"cat", "lion"});
  const std::vector<std::string> presets = env_list("NF_BENCH_FUR_PRESETS", options.quick ? std::vector<std::string>{"draft"} : std::vector<std::string>{"draft", "default"});
  const std::vector<std::string> variants =
      env_list("NF_BENCH_FUR_VARIANTS", options.quick ? std::vector<std::string>{"truth_all"}
                                                      : std::vector<std::string>{"truth_all", "truth_knowledge", "warm_off", "no_silhouette", "no_orientation",
                                                                                 "no_direction", "no_chamfer", "no_penetration", "no_curvature",
                                                                                 "truth_knowledge_file", "truth_envelope",
                                                                                 "truth_envelope+truth_knowledge_file", "select_trained", "lengths", "patches",
                                                                                 "true_orientation", "knowledge_turned"});
  for (const std::string& v : variants) variant_settings(v, root);  // unknown names fail before any work
  for (const std::string& p : presets)
    if (p != "draft" && p != "default" && p != "paper") throw UsageError("NF_BENCH_FUR_PRESETS: unknown preset '" + p + "' (draft, default, paper)");
  const double curve_seconds = options.quick ? 10 : 60;
  // NF_BENCH_FUR_FRAME: the world frame the scenes are written in (synth --frame), so the whole
  // bench can be run in a studio's z-up millimetres and compared with the default y-up metres.
  const char* frame_env = std::getenv("NF_BENCH_FUR_FRAME");
  const std::string frame = frame_env && *frame_env ? frame_env : "y-up-m";
  if (const auto names = synth::world_frame_names(); std::find(names.begin(), names.end(), frame) == names.end())
    throw UsageError("NF_BENCH_FUR_FRAME: unknown frame '" + frame + "' (" + join(names) + ")");

  // NF_BENCH_FUR_RESOLUTIONS: the photos' sizes (longer side; default 512, 128 with --quick); a
  // scene of another size than 512 is named after it (cat-1024).
  std::vector<std::uint32_t> resolutions;
  for (const std::string& r : env_list("NF_BENCH_FUR_RESOLUTIONS", {options.quick ? "128" : "512"})) {
    char* end = nullptr;
    const unsigned long v = std::strtoul(r.c_str(), &end, 10);
    if (r.empty() || *end || v < 64 || v > 8192) throw UsageError("NF_BENCH_FUR_RESOLUTIONS: '" + r + "' is not a photo size in [64, 8192]");
    resolutions.push_back(std::uint32_t(v));
  }

  json records = json::array();
  for (const std::uint32_t resolution : resolutions)
  for (const std::string& animal : animals) {
    const bool sized = resolution != (options.quick ? 128u : 512u);
    const std::string named = (frame == "y-up-m" ? animal : animal + "-" + frame) + (sized ? "-" + std::to_string(resolution) : "");
    const fs::path scene = root / named, work = root / (named + "-work");
    synth::SynthOptions so;
    so.animal = animal, so.seed = 1, so.frame = frame;
    so.views = options.quick ? 12 : 36;
    so.resolution = resolution;
    so.strands = options.quick ? 20000 : 100000;
    so.true_orientation = true;  // for the true_orientation variant
    if (!fs::exists(scene / "gt" / "scene.json")) synth::synthesize_scene(scene, so);
    const json scene_params{{"animal", animal}, {"frame", frame}, {"views", so.views}, {"resolution", so.resolution}, {"gt_strands", so.strands}};

    for (std::size_t p = 0; p < presets.size(); ++p) {
      // The earlier stages at draft (the same surface, body and roots for every preset and
      // variant); the fur stage at the preset's values, with its curve.
      std::vector<std::string> fur_preset;
      const json preset_values = pipeline::fur_settings().values(presets[p], json::object());
      for (const auto& [key, value] : preset_values.items())
        fur_preset.push_back("fur." + key + "=" + (value.is_string() ? value.get<std::string>() : value.dump()));
      std::vector<std::string> runs{""};
      if (p == 0) runs.insert(runs.end(), variants.begin(), variants.end());
      for (const std::string& variant : runs) {
        const std::vector<std::string> swaps = variant_settings(variant, scene);
        if (variant.find("knowledge_turned") != std::string::npos) write_turned_knowledge(scene);
        // A variant that changes a stage before fur works in its own copy of the preset run's WORK,
        // so the shared earlier stages stay as they are for the other runs.
        const bool own_work = sets_stage(swaps, "neus") || sets_stage(swaps, "knowledge");
        const fs::path run_work = own_work ? root / (named + "-work-" + variant) : work;
        if (own_work) {  // fresh each time: an old copy may hold other earlier stages, or half a copy
          const fs::path partial = run_work.string() + ".partial";
          fs::remove_all(run_work);
          fs::remove_all(partial);
          fs::copy(work, partial, fs::copy_options::recursive);
          fs::rename(partial, run_work);
        }
        pipeline::ReconstructOptions ro;
        ro.scene = scene, ro.work = run_work, ro.quality = "draft";
        ro.run.to = "fur";
        ro.settings.clear();
        if (!sets_stage(swaps, "knowledge")) ro.settings.push_back("knowledge.preset=" + animal);
        if (options.quick) ro.settings.push_back("neus.steps=150");
        ro.settings.insert(ro.settings.end(), fur_preset.begin(), fur_preset.end());
        // The groom's inference is not what is measured: the metrics' strands suffice.
        ro.settings.push_back("fur.strands=" + std::to_string(pipeline::fur_settings().resolve(presets[p], json::object()).metric_strands));
        ro.settings.push_back("fur.curve_seconds=" + json(curve_seconds).dump());
        ro.settings.push_back("fur.preview_views=0");
        if (options.quick) ro.settings.insert(ro.settings.end(), {"fur.steps=60", "fur.warm_steps=10", "fur.batch=1500", "fur.resolution=128"});
        ro.settings.insert(ro.settings.end(), swaps.begin(), swaps.end());
        log::info("bench fur: ", named, ", preset ", presets[p], variant.empty() ? "" : ", variant " + variant);
        const std::vector<pipeline::StageOutcome> outcomes = pipeline::reconstruct(ctx, ro);
        const json m = read_json(pipeline::fur_outputs(run_work).metrics());

        json stage_seconds = json::object();
        for (const pipeline::StageOutcome& o : outcomes) stage_seconds[o.name] = {{"seconds", o.seconds}, {"ran", o.ran}};
        json metrics{{"groom", groom_summary(m.at("groom"))},
                     {"held_out", held_out_summary(m["held_out"])},
                     {"steps", m.at("steps")},
                     {"strands_per_step", m.at("training_strands_per_step")},
                     {"seconds_per_step", m.at("seconds_per_step")},
                     {"pass_seconds_last_step", m["final"].value("pass_seconds", json::object())},
                     {"skipped_steps", m.at("skipped_steps")},
                     {"orientation_reliability", m["views"]["orientation_reliability"]},
                     {"fur_pixels_median", m["views"]["fur_pixels_median"]},
                     {"image_weight_mean", m["views"]["image_weight_mean"]},
                     {"rendered_fraction_of_photo", m["views"]["rendered_fraction_of_photo"]},
                     {"stages", stage_seconds},
                     {"selection", m.value("selection", json::object())},
                     {"lengths", m.value("lengths", json::object())},
                     {"colors", colors_summary(m.value("colors", json::object()))},
                     {"fur_seconds", m.at("seconds")}};
        // The baseline groom on the roots this run used: (a) on the pipeline's, (b) on the truth's.
        const bool true_inputs = std::find(swaps.begin(), swaps.end(), "fur.truth=all") != swaps.end();
        metrics[true_inputs ? "baseline_b" : "baseline_a"] = groom_summary(m.at("baseline"));
        json points = json::array();
        for (const json& c : m.at("curve"))
          if (c.contains("fscore")) points.push_back({c["seconds"], c["fscore"]["2cm_20deg"]});
        metrics["curve_points"] = m.at("curve");
        json params = scene_params;
        params["preset"] = presets[p];
        params["variant"] = variant.empty() ? "none" : variant;
        params["earlier_stages"] = "draft";
        Timing timing;
        timing.seconds = {m.at("seconds_total").get<double>()};
        json record = make_record(ctx, "fur", named + "_" + presets[p] + (variant.empty() ? "" : "_" + variant), params, timing, metrics);
        record["curve"] = {{"x", "training seconds"}, {"y", "F-score at (2 cm, 20 deg), %"}, {"points", points}};
        records.push_back(record);
      }
    }
  }
  return records;
}

}  // namespace nf::bench
