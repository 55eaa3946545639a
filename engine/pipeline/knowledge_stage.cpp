#include "engine/pipeline/knowledge_stage.hpp"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <optional>

#include "engine/core/atomic_file.hpp"
#include "engine/core/content_hash.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/text.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/knowledge/annotation_photos.hpp"
#include "engine/knowledge/consensus.hpp"
#include "engine/knowledge/metric_scale.hpp"
#include "engine/knowledge/prompts.hpp"
#include "engine/knowledge/vlm_annotation.hpp"
#include "engine/knowledge/vlm_client.hpp"
#include "engine/knowledge/vlm_session.hpp"
#include "engine/pipeline/body_stage.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr int kStageVersion = 4;  // 2: the body length as a second scale cue; 3: the photos' eyes; 4: the spread widened when cues disagree

std::string source_help() {
  return "name one source of fur knowledge: --set knowledge.preset=NAME (presets: " + join(knowledge::preset_names()) +
         "), --set knowledge.file=FILE (a knowledge.json), or --set knowledge.vlm=URL --set knowledge.model=NAME (any "
         "OpenAI-compatible endpoint; the API key from " + std::string(kVlmKeyVariable) + ")";
}

// The transcript is written under the stage's resume folder, which survives a failure, and copied
// into the outputs on success: after an error it is still there to read.
json annotate_with_vlm(const StageContext& c, const KnowledgeSettings& s, const KnowledgeOutputs& out, const fs::path& resume,
                       const glm::dmat4& animal_to_world, knowledge::Knowledge& result, std::vector<std::string>& warnings) {
  knowledge::VlmEndpoint endpoint;
  endpoint.url = s.vlm, endpoint.model = s.model;
  if (const char* key = std::getenv(kVlmKeyVariable)) {  // without the spaces or line break a paste brings
    std::string k = key;
    k.erase(0, k.find_first_not_of(" \t\r\n"));
    k.erase(k.find_last_not_of(" \t\r\n") + 1);
    endpoint.api_key = k;
  }
  if (endpoint.api_key.empty()) log::info("knowledge: ", kVlmKeyVariable, " is not set: no API key is sent (fine for a local server)");
  endpoint.timeout_s = s.timeout_s, endpoint.retries = s.retries, endpoint.retry_wait_s = s.retry_wait_s;
  endpoint.max_answer_bytes = std::size_t(s.max_answer_mb * 1024.0 * 1024.0);
  endpoint.temperature = s.temperature;

  const knowledge::AnnotationPhotos photos = knowledge::annotation_photos(c.scene, animal_to_world, std::uint32_t(s.image_size));
  fs::create_directories(out.images());
  write_file_atomic(out.images() / "frontal.jpg", photos.frontal.jpeg);
  write_file_atomic(out.images() / "side_axes.jpg", photos.side_with_axes.jpeg);
  const knowledge::AnnotationImages images{photos.frontal.data_url(), photos.side_with_axes.data_url()};

  const fs::path transcript = resume / "transcript.jsonl";
  std::optional<knowledge::VlmSession> open_session;
  open_session.emplace(endpoint, c.work / ".cache" / "knowledge", transcript);
  knowledge::VlmSession& session = *open_session;
  session.name_image(images.frontal, "images/frontal.jpg");
  session.name_image(images.side_with_axes, "images/side_axes.jpg");
  std::vector<knowledge::Knowledge> samples;
  // An answer that stays unusable falls back on the animal's preset when `animal` names one.
  const std::vector<std::string> presets = knowledge::preset_names();
  std::optional<knowledge::Knowledge> fallback;
  if (std::find(presets.begin(), presets.end(), s.animal) != presets.end()) fallback = knowledge::preset(s.animal);
  const knowledge::ChatFunction chat = [&](const json& messages, const std::string& step) { return session.chat(messages, step); };
  for (int k = 0; k < s.samples; ++k) {
    session.set_sample(k);
    const std::string where = "knowledge (VLM " + s.model + (s.samples > 1 ? ", sample " + std::to_string(k + 1) : "") + ")";
    knowledge::Annotation a;
    try {
      a = knowledge::annotate_with_vlm(chat, images, where, fallback ? &*fallback : nullptr);
    } catch (const InputError& e) {
      session.forget_sample();
      throw InputError(std::string(e.what()) + " (the conversation: " + transcript.string() + ")" +
                       (fallback ? std::string() : "; --set knowledge.animal=PRESET (" + join(presets) + ") lets a preset's values stand in"));
    }
    session.keep_sample();
    for (const std::string& w : a.warnings) warnings.push_back((s.samples > 1 ? "sample " + std::to_string(k + 1) + ": " : "") + w);
    samples.push_back(std::move(a.knowledge));
  }
  warnings.insert(warnings.end(), session.warnings.begin(), session.warnings.end());
  const int sent = session.sent, cached = session.from_cache, attempts = session.attempts;
  const std::size_t request_bytes = session.request_bytes, answer_bytes = session.answer_bytes;
  open_session.reset();  // closes the transcript
  fs::copy_file(transcript, out.transcript(), fs::copy_options::overwrite_existing);
  json summary{{"model", s.model},
               {"url", knowledge::redacted_url(knowledge::chat_completions_url(s.vlm))},
               {"photos", {{"frontal", c.scene.cameras[photos.frontal.camera].name}, {"side", c.scene.cameras[photos.side_with_axes.camera].name},
                           {"image_bytes", photos.frontal.jpeg.size() + photos.side_with_axes.jpeg.size()}}},
               {"samples", s.samples},
               {"requests_sent", sent},
               {"requests_from_cache", cached},
               {"http_attempts", attempts},
               {"request_bytes", request_bytes},
               {"answer_bytes", answer_bytes}};
  if (samples.size() > 1) {
    knowledge::Consensus agreed = knowledge::consensus(samples);
    result = std::move(agreed.knowledge);
    write_file_atomic(out.consensus(), json{{"samples", samples.size()}, {"spread", agreed.spread}, {"flagged", agreed.flagged}}.dump(2) + "\n");
    if (!agreed.flagged.empty())
      warnings.push_back("the " + std::to_string(samples.size()) + " answers disagree (lengths by more than a factor of two, "
                         "bald against furred, or directions) on " + join(agreed.flagged) + " (consensus.json has the spread)");
    summary["flagged"] = agreed.flagged;
  } else {
    result = std::move(samples[0]);
  }
  result.animal = s.animal;
  result.source = "vlm:" + s.model;
  return summary;
}

// How the fitted body and the scale compare with an `nf_gpu synth` scene's ground truth.
json ground_truth_metrics(const StageContext& c, const knowledge::ScaleInputs& inputs, const knowledge::MetricScale& scale, const glm::dmat4& fitted) {
  const std::optional<io::GroundTruth> gt = io::find_ground_truth(c.scene_dir);
  if (!gt) return json();
  json out{{"cm_per_unit", gt->cm_per_unit}, {"scale_error", scale.cm_per_unit / gt->cm_per_unit - 1.0}};
  if (scale.from_eyes) out["scale_from_eyes_error"] = *scale.from_eyes / gt->cm_per_unit - 1.0;
  if (scale.from_cues) out["scale_from_cues_error"] = *scale.from_cues / gt->cm_per_unit - 1.0;
  for (const knowledge::ScaleCue& cue : scale.cues) out["scale_cue_errors"][cue.name] = cue.cm_per_unit / gt->cm_per_unit - 1.0;
  if (scale.from_cues) {  // whether the spread the cues report covers the truth
    out["scale_cues_spread"] = scale.cues_spread;
    out["scale_covered"] = std::fabs(std::log(*scale.from_cues / gt->cm_per_unit)) <= scale.cues_spread;
  }
  const io::JsonField info(gt->info, gt->scene_json().string());
  if (const auto eye = info.find("eye_distance_cm")) {
    out["eye_distance_error"] = inputs.eye_distance_units * gt->cm_per_unit / eye->number() - 1.0;
    // The cues for an individual whose eyes are as far apart as the knowledge says: its own eye
    // distance in place of the knowledge's (what is left is the measurement's error and the body
    // length's).
    knowledge::ScaleInputs own = inputs;
    own.eye_distance_cm = eye->number();
    own.scene_declared.reset(), own.user_given.reset();
    if (own.eye_distance_units > 0) {
      const knowledge::MetricScale m = knowledge::metric_scale(own);
      if (m.from_cues) out["scale_from_cues_error_own_eyes"] = *m.from_cues / gt->cm_per_unit - 1.0;
      if (m.from_eyes) out["scale_from_eyes_error_own_eyes"] = *m.from_eyes / gt->cm_per_unit - 1.0;
    }
  }
  if (const auto rows = info.find("animal_to_world")) {
    const glm::dmat4 truth = io::matrix_rows(*rows);
    const auto angle = [&](int axis) {
      const double d = glm::dot(glm::normalize(glm::dvec3(fitted[axis])), glm::normalize(glm::dvec3(truth[axis])));
      return std::acos(std::clamp(d, -1.0, 1.0)) * 180.0 / 3.14159265358979;
    };
    out["frame_error_degrees"] = {{"left", angle(0)}, {"up", angle(1)}, {"forward", angle(2)}};
  }
  return out;
}

}  // namespace

double read_metric_scale(const KnowledgeOutputs& outputs) {
  const json j = io::read_json_file(outputs.scale());
  const double v = io::JsonField(j, outputs.scale().string()).at("cm_per_unit").number();
  if (!(std::isfinite(v) && v > 0)) throw InputError(outputs.scale().string() + ": cm_per_unit must be positive");
  return v;
}

void KnowledgeStage::check_needed_settings(const std::string& quality, const json& overrides) const {
  const KnowledgeSettings s = knowledge_settings().resolve(quality, overrides);
  if (s.file.empty() && s.preset.empty() && s.vlm.empty())
    throw UsageError("stage knowledge: " + source_help() + "; or stop before it with --to body");
}

std::array<glm::vec3, body::kRegionCount> read_directions_world(const KnowledgeOutputs& outputs) {
  const json j = io::read_json_file(outputs.directions_world());
  const io::JsonField directions = io::JsonField(j, outputs.directions_world().string()).at("directions");
  std::array<glm::vec3, body::kRegionCount> out{};
  for (int r = 0; r < body::kRegionCount; ++r) {
    const auto d = directions.find(body::kRegionNames[std::size_t(r)]);
    if (!d) continue;
    glm::dvec3 v;
    for (int c = 0; c < 3; ++c) v[c] = d->at(std::size_t(c)).number();
    const double n = glm::length(v);
    if (!(std::isfinite(n) && n > 0.5 && n < 1.5)) d->fail("expected a unit vector");
    out[std::size_t(r)] = glm::vec3(v / n);
  }
  return out;
}

std::vector<fs::path> KnowledgeStage::inputs(const StageContext& c) const {
  const BodyOutputs body = body_outputs(c.work);
  std::vector<fs::path> files{body.animal_frame(), body.eyes()};
  const KnowledgeSettings s = settings_of(c);
  if (!s.file.empty()) files.push_back(s.file);
  if (!s.vlm.empty())  // the photos sent are chosen from all of them
    for (const io::Camera& cam : c.scene.cameras)
      for (const fs::path& f : {cam.image, cam.mask})
        if (!f.empty()) files.push_back(f);
  if (const auto gt = io::find_ground_truth(c.scene_dir)) files.push_back(gt->scene_json());
  return files;
}

json KnowledgeStage::parameters(const StageContext& c) const {
  std::string prompts = knowledge::system_prompt();
  for (const knowledge::Prompt& p : knowledge::paper_prompts()) prompts += p.message();
  json settings = settings_values(knowledge_settings(), c);
  // The stage key is written to disk: a user name, password or key inside the URL stays out of it.
  const std::string vlm = settings.value("vlm", std::string());
  if (!vlm.empty()) settings["vlm"] = knowledge::redacted_url(vlm) + " #" + hash_bytes(vlm);
  return {{"stage_version", kStageVersion},
          {"settings", settings},
          {"prompts", hash_bytes(prompts)},
          {"scene_cm_per_unit", c.scene.cm_per_unit ? json(*c.scene.cm_per_unit) : json()}};
}

json KnowledgeStage::run(StageContext& c, const fs::path& out_dir, const fs::path& resume) {
  const KnowledgeSettings s = settings_of(c);
  const KnowledgeOutputs out{out_dir};
  const BodyOutputs body = body_outputs(c.work);
  const auto t0 = std::chrono::steady_clock::now();

  const glm::dmat4 animal_to_world = read_animal_to_world(body);
  const double eye_units = read_eye_distance(body);
  const std::optional<double> body_length_units = read_head_and_body_length(body);

  knowledge::Knowledge k;
  std::vector<std::string> warnings;
  json summary = json::object();
  if (!s.file.empty()) {
    k = knowledge::read_knowledge(s.file);
    k.source = "file";
    summary["file"] = fs::absolute(s.file).string();
  } else if (!s.preset.empty()) {
    k = knowledge::preset(s.preset);
  } else if (!s.vlm.empty()) {
    summary["vlm"] = annotate_with_vlm(c, s, out, resume, animal_to_world, k, warnings);
  } else {
    throw UsageError("stage knowledge: " + source_help());
  }
  summary["source"] = k.source;
  knowledge::write_knowledge(out.knowledge(), k);

  // Directions in the world: the animal frame's axes (x left, y up, z forward) through the fit.
  const glm::dvec3 left = glm::normalize(glm::dvec3(animal_to_world[0])), up = glm::normalize(glm::dvec3(animal_to_world[1])),
                   forward = glm::normalize(glm::dvec3(animal_to_world[2]));
  json world = json::object();
  for (int r = 0; r < body::kRegionCount; ++r)
    if (k.regions[std::size_t(r)]) {
      const glm::dvec3 d(k.regions[std::size_t(r)]->direction);
      world[std::string(body::kRegionNames[std::size_t(r)])] = json_vec3(glm::normalize(d.x * left + d.y * up + d.z * forward));
    }
  write_file_atomic(out.directions_world(), json{{"frame", "world (the scene's axes), through WORK/body/animal_frame.json"},
                                                 {"directions", world}}.dump(2) + "\n");

  knowledge::ScaleInputs scale_inputs;
  scale_inputs.eye_distance_cm = k.eye_distance_cm, scale_inputs.eye_distance_units = eye_units;
  scale_inputs.eyes_from_photos = read_eyes_from_photos(body);
  if (k.body_length_cm) scale_inputs.body_length_cm = *k.body_length_cm;
  scale_inputs.body_length_units = body_length_units;
  scale_inputs.scene_declared = c.scene.cm_per_unit;
  if (s.cm_per_unit > 0) scale_inputs.user_given = s.cm_per_unit;
  const knowledge::MetricScale scale = knowledge::metric_scale(scale_inputs);
  if (!scale.warning.empty()) warnings.push_back(scale.warning);
  json scale_json = knowledge::to_json(scale);
  scale_json["eye_distance_cm"] = k.eye_distance_cm;
  scale_json["eye_distance_units"] = eye_units;
  write_file_atomic(out.scale(), scale_json.dump(2) + "\n");
  std::string cue_text;
  for (const knowledge::ScaleCue& cue : scale.cues)
    cue_text += "; the " + cue.name + (cue.name == "eyes" ? " say " : " says ") + std::to_string(cue.cm_per_unit);
  log::info("knowledge: ", scale.cm_per_unit, " cm per scene unit (from ", scale.source,
            scale.spread > 0 ? ", +-" + std::to_string(std::lround(100 * scale.spread)) + " %" : std::string(), ")", cue_text);

  for (const std::string& w : warnings) log::warn("knowledge: ", w);
  summary["scale"] = scale_json;
  summary["warnings"] = warnings;
  int furred = 0;
  for (int r = 0; r < body::kRegionCount; ++r) furred += k.grows_fur(body::Region(r)) ? 1 : 0;
  summary["regions_with_fur"] = furred;
  const json gt = ground_truth_metrics(c, scale_inputs, scale, animal_to_world);
  if (!gt.is_null()) summary["ground_truth"] = gt;
  summary["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_file_atomic(out.metrics(), dump_text(summary, 2) + "\n");
  return summary;
}

const SettingsSchema<KnowledgeSettings>& knowledge_settings() {
  using K = KnowledgeSettings;
  static const SettingsSchema<K> schema = [] {
    SettingsSchema<K> s("knowledge", [](const std::string&) { return K{}; });
    s.text("preset", [](K& k) -> auto& { return k.preset; }, knowledge::preset_names(), "a built-in annotation (assets/knowledge)")
        .text("file", [](K& k) -> auto& { return k.file; }, {}, "a knowledge.json of your own (e.g. an edited WORK/knowledge/knowledge.json)")
        .text("vlm", [](K& k) -> auto& { return k.vlm; }, {},
              "an OpenAI-compatible endpoint, e.g. https://api.openai.com/v1 or http://localhost:11434 (Ollama)")
        .text("model", [](K& k) -> auto& { return k.model; }, {}, "the VLM's model name, e.g. gpt-4o or qwen2.5vl")
        .text("animal", [](K& k) -> auto& { return k.animal; }, {},
              "the animal's name written into a VLM annotation; a preset's name (cat, dog, ...) also makes its values stand in for "
              "answers that stay unusable")
        .add("samples", [](K& k) -> auto& { return k.samples; }, 1, 25, "VLM: independent annotations; more than 1 takes their consensus")
        .add("image_size", [](K& k) -> auto& { return k.image_size; }, 64, 4096, "VLM: longer side of the photos sent, pixels")
        .add("timeout_s", [](K& k) -> auto& { return k.timeout_s; }, 1, 3600, "VLM: seconds one request may take")
        .add("retries", [](K& k) -> auto& { return k.retries; }, 0, 20, "VLM: further attempts after HTTP 429, 5xx or a lost connection")
        .add("retry_wait_s", [](K& k) -> auto& { return k.retry_wait_s; }, 0, 600, "VLM: first wait before a retry (doubles each time)")
        .add("max_answer_mb", [](K& k) -> auto& { return k.max_answer_mb; }, 0.01, 1024, "VLM: larger answers are refused")
        .add("temperature", [](K& k) -> auto& { return k.temperature; }, -1, 2, "VLM: sampling temperature; -1 sends none (the server's default)")
        .add("cm_per_unit", [](K& k) -> auto& { return k.cm_per_unit; }, 0, 1e9,
             "the scene's scale in cm per unit (--scene-scale); 0: the scene file's, else from the eyes")
        .check([](const K& k) {
          const int sources = int(!k.file.empty()) + int(!k.preset.empty()) + int(!k.vlm.empty());
          if (sources > 1) throw UsageError("knowledge.file, knowledge.preset and knowledge.vlm are alternatives: give one");
          if (!k.vlm.empty() && k.model.empty()) throw UsageError("knowledge.vlm needs knowledge.model (the model's name at that endpoint)");
          if (k.vlm.empty() && !k.model.empty()) throw UsageError("knowledge.model is for a VLM: give knowledge.vlm=URL too");
          if (!k.vlm.empty()) (void)knowledge::chat_completions_url(k.vlm);
          if (!k.file.empty() && !fs::is_regular_file(k.file)) throw UsageError("knowledge.file=" + k.file + ": no such file");
        });
    return s;
  }();
  return schema;
}

}  // namespace nf::pipeline
