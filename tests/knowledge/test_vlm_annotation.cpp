// One VLM annotation without a network (a scripted model): the paper's prompts asked in order as one
// conversation with the photos in the first message, a single retry of an unusable answer, the fill
// rules for regions left out, the consensus of several annotations and the metric scale.
#include <doctest/doctest.h>

#include <random>

#include "engine/core/error.hpp"
#include "engine/knowledge/answer_parsing.hpp"
#include "engine/knowledge/consensus.hpp"
#include "engine/knowledge/metric_scale.hpp"
#include "engine/knowledge/prompts.hpp"
#include "engine/knowledge/vlm_annotation.hpp"
#include "tests/knowledge/recorded_answers.hpp"

using namespace nf;
using namespace nf::knowledge;
using body::Region;

namespace {

struct ScriptedModel {
  std::map<std::string, std::string> answers = test::good_answers();
  std::vector<json> requests;
  std::vector<std::string> steps;
  std::string operator()(const json& messages, const std::string& step) {
    requests.push_back(messages);
    steps.push_back(step);
    const std::string asked = test::asked_step(messages);
    const auto it = answers.find(asked);
    return it != answers.end() ? it->second : std::string();
  }
};

const AnnotationImages kImages{"data:image/jpeg;base64,AAAA", "data:image/jpeg;base64,BBBB"};

}  // namespace

TEST_CASE("the paper's five prompts, the hair's and the body length's, one conversation, the photos first") {
  ScriptedModel model;
  const Annotation a = annotate_with_vlm(std::ref(model), kImages, "test");
  REQUIRE(model.requests.size() == 7);
  CHECK(model.steps == std::vector<std::string>{"length", "thickness", "verify", "direction", "eyes", "hair", "body"});
  // Each request carries everything before it: the system prompt, the questions and the answers.
  for (std::size_t i = 0; i < 7; ++i) CHECK(model.requests[i].size() == 2 + 2 * i);
  CHECK(model.requests[0][0]["role"] == "system");
  const json& first = model.requests[0][1]["content"];
  REQUIRE(first.is_array());
  CHECK(first[0]["image_url"]["url"] == kImages.frontal);
  CHECK(first[1]["image_url"]["url"] == kImages.side_with_axes);
  CHECK(first[2]["text"].get<std::string>().find(paper_prompts()[0].text) == 0);  // the paper's words, verbatim
  CHECK(model.requests[4][8]["content"] == test::good_answers()["direction"]);    // later prompts see earlier answers

  const Knowledge& k = a.knowledge;
  CHECK(k.eye_distance_cm == doctest::Approx(3.2));
  CHECK(k.at(Region::body).length_cm == doctest::Approx(1.1));  // the verification's correction
  CHECK(k.at(Region::tail).length_cm == doctest::Approx(1.4));
  CHECK(k.at(Region::body).thickness_cm == doctest::Approx(0.4));
  CHECK(k.at(Region::leg_rear).length_cm == doctest::Approx(0.9));  // kept from the first answer
  CHECK(k.grows_fur(Region::mane));
  CHECK_FALSE(k.grows_fur(Region::eyes));
  CHECK(glm::length(k.at(Region::neck).direction) == doctest::Approx(1.0));
  CHECK(k.hair_diameter_mm == doctest::Approx(0.06));
  REQUIRE(k.body_length_cm.has_value());
  CHECK(*k.body_length_cm == doctest::Approx(46));
  CHECK(a.requests == 7);
}

TEST_CASE("the head-and-body length: read in cm, m or prose, never a tail's; no usable answer leaves the eyes alone with a warning") {
  CHECK(body_length_cm_of(R"({"body_length_cm": 46})", "body") == doctest::Approx(46));
  CHECK(body_length_cm_of(R"({"tail_length_cm": 30, "head_and_body_length": "0.5 m"})", "body") == doctest::Approx(50));
  CHECK(body_length_cm_of("An adult lion measures 1.9 m from nose to tail base.", "body") == doctest::Approx(190));
  CHECK(body_length_cm_of(R"({"length_cm": 5, "body_length_m": 1.9})", "body") == doctest::Approx(190));  // the body's key first, in m
  CHECK_THROWS_WITH_AS(body_length_cm_of("Hard to say.", "body"), doctest::Contains("no length"), InputError);
  ScriptedModel vague;
  vague.answers["body"] = "It depends on the breed.";
  const Annotation a = annotate_with_vlm(std::ref(vague), kImages, "test");
  CHECK(a.requests == 8);  // asked once more, then none
  CHECK_FALSE(a.knowledge.body_length_cm.has_value());
  CHECK(std::any_of(a.warnings.begin(), a.warnings.end(), [](const std::string& w) { return w.find("rests on the eyes") != std::string::npos; }));
  ScriptedModel huge;
  huge.answers["body"] = R"({"body_length_cm": 4000})";
  CHECK_FALSE(annotate_with_vlm(std::ref(huge), kImages, "test").knowledge.body_length_cm.has_value());
}

TEST_CASE("an answer that stays unusable: the animal's preset stands in for the values refused, and knowledge.json says so") {
  const Knowledge cat = preset("cat");
  // One region out of range twice: that region takes the preset's length, the rest of the answer stands.
  ScriptedModel one;
  one.answers["length"] = R"({"body": 1.1, "tail": 75, "ears": 0.3})";
  one.answers["verify"] = R"({"thickness": {"body": 0.4}})";
  const Annotation a = annotate_with_vlm(std::ref(one), kImages, "test", &cat);
  CHECK(a.knowledge.at(Region::tail).length_cm == doctest::Approx(cat.at(Region::tail).length_cm));
  CHECK(a.knowledge.at(Region::body).length_cm == doctest::Approx(1.1));
  CHECK(a.knowledge.at(Region::ears).length_cm == doctest::Approx(0.3));
  CHECK(a.knowledge.origin.at("regions.tail.length_cm") == "preset:cat");
  CHECK(a.knowledge.origin.count("regions.body.length_cm") == 0);
  CHECK(std::any_of(a.warnings.begin(), a.warnings.end(), [](const std::string& w) {
    return w.find("regions.tail.length_cm: the answers stayed unusable; the preset:cat value stands") != std::string::npos;
  }));
  // Nothing readable: the whole field is the preset's.
  ScriptedModel none;
  none.answers["direction"] = "I cannot tell from these photos.";
  const Annotation b = annotate_with_vlm(std::ref(none), kImages, "test", &cat);
  CHECK(b.knowledge.at(Region::tail).direction == cat.at(Region::tail).direction);
  CHECK(b.knowledge.origin.at("regions.ears.direction") == "preset:cat");
  ScriptedModel blind;
  blind.answers["eyes"] = "No idea.";
  const Annotation c = annotate_with_vlm(std::ref(blind), kImages, "test", &cat);
  CHECK(c.knowledge.eye_distance_cm == doctest::Approx(cat.eye_distance_cm));
  CHECK(c.knowledge.origin.at("eye_distance_cm") == "preset:cat");
  // The refused region is `body`, which the length answer must give: the preset gives it, the rest stands.
  ScriptedModel no_body;
  no_body.answers["length"] = R"({"body": 75, "tail": 2})";
  no_body.answers["verify"] = R"({"thickness": {"body": 0.4}})";
  const Annotation d = annotate_with_vlm(std::ref(no_body), kImages, "test", &cat);
  CHECK(d.knowledge.at(Region::body).length_cm == doctest::Approx(cat.at(Region::body).length_cm));
  CHECK(d.knowledge.at(Region::tail).length_cm == doctest::Approx(2.0));
  CHECK(d.knowledge.origin.at("regions.body.length_cm") == "preset:cat");
  // A verify answer that stays out of range keeps the values before it.
  ScriptedModel wild;
  wild.answers["verify"] = R"({"length": {"body": 90}})";
  const Annotation e = annotate_with_vlm(std::ref(wild), kImages, "test", &cat);
  CHECK(e.knowledge.at(Region::body).length_cm == doctest::Approx(1.0));
  // Without a preset the stage still stops, naming the region and field.
  CHECK_THROWS_WITH_AS(annotate_with_vlm(std::ref(one), kImages, "test"), doctest::Contains("regions.tail.length_cm = 75"), InputError);
  // The fill rules are recorded too, and the record survives knowledge.json.
  CHECK(a.knowledge.origin.at("regions.under_tail.length_cm") == "filled from tail");
  const Knowledge back = knowledge_from_json(knowledge_to_json(a.knowledge), "k.json");
  CHECK(back.origin == a.knowledge.origin);
}

TEST_CASE("the hair's diameter: read in mm, um or prose; no usable answer keeps the default with a warning") {
  CHECK(hair_diameter_mm_of(R"({"hair_diameter_mm": 0.07})", "hair") == doctest::Approx(0.07));
  CHECK(hair_diameter_mm_of(R"({"diameter": "70 um"})", "hair") == doctest::Approx(0.07));
  CHECK(hair_diameter_mm_of(R"({"diameter": "0.05"})", "hair") == doctest::Approx(0.05));
  CHECK(hair_diameter_mm_of(R"({"hair_length_cm": 3, "hair_diameter_um": 60})", "hair") == doctest::Approx(0.06));  // not the length
  CHECK(hair_diameter_mm_of(R"({"hair": 0.2, "diameter_cm": 0.008})", "hair") == doctest::Approx(0.08));  // the diameter's key first
  CHECK(hair_diameter_mm_of("A cat's guard hair is about 60 \xc2\xb5m across.", "hair") == doctest::Approx(0.06));
  CHECK(hair_diameter_mm_of("Roughly 0.05-0.09 mm.", "hair") == doctest::Approx(0.07));
  CHECK_THROWS_WITH_AS(hair_diameter_mm_of("I cannot tell.", "hair"), doctest::Contains("no diameter"), InputError);

  ScriptedModel vague;
  vague.answers["hair"] = "It depends on the breed.";
  const Annotation a = annotate_with_vlm(std::ref(vague), kImages, "test");
  CHECK(a.requests == 8);  // asked once more, then the default
  CHECK(a.knowledge.hair_diameter_mm == doctest::Approx(kDefaultHairDiameterMm));
  CHECK(std::any_of(a.warnings.begin(), a.warnings.end(), [](const std::string& w) { return w.find("no usable hair diameter") != std::string::npos; }));
  ScriptedModel huge;
  huge.answers["hair"] = R"({"hair_diameter_mm": 3})";  // 3 mm: a fur layer's thickness, not a hair
  CHECK(annotate_with_vlm(std::ref(huge), kImages, "test").knowledge.hair_diameter_mm == doctest::Approx(kDefaultHairDiameterMm));
}

TEST_CASE("an unusable answer is asked again once, then refused with the region and field") {
  ScriptedModel model;
  model.answers["length"] = R"({"body": 75, "tail": 2})";
  CHECK_THROWS_WITH_AS(annotate_with_vlm(std::ref(model), kImages, "test"),
                       doctest::Contains("length prompt: regions.body.length_cm = 75"), InputError);
  CHECK(model.steps == std::vector<std::string>{"length", "length-retry"});
  CHECK(test::prompt_step(model.requests[1]) == "retry");

  // Fixed on the second try: the run goes on, with a warning.
  ScriptedModel fixed;
  int calls = 0;
  const ChatFunction chat = [&](const json& messages, const std::string& step) {
    ++calls;
    return calls == 1 ? std::string("I think the fur is long.") : fixed(messages, step);
  };
  const Annotation a = annotate_with_vlm(chat, kImages, "test");
  CHECK(a.requests == 8);
  CHECK(std::any_of(a.warnings.begin(), a.warnings.end(), [](const std::string& w) { return w.find("asked again") != std::string::npos; }));

  // [0, 0, 0] is "no direction": on the bald eyes it passes silently, on the furred body the body
  // takes the fill rule's direction (down) with a warning naming it, and the stage goes on.
  ScriptedModel zero;
  zero.answers["direction"] = R"({"body": [0, 0, 0], "tail": [0, 0, -1], "eyes": [0, 0, 0], "nosetip": [0, 0, 0]})";
  const Annotation z = annotate_with_vlm(std::ref(zero), kImages, "test");
  CHECK(z.requests == 7);  // not asked again
  CHECK(z.knowledge.at(Region::body).direction == glm::vec3(0, -1, 0));
  CHECK(z.knowledge.at(Region::tail).direction == glm::vec3(0, 0, -1));
  const auto zero_warning = std::find_if(z.warnings.begin(), z.warnings.end(), [](const std::string& w) { return w.find("no direction") != std::string::npos; });
  REQUIRE(zero_warning != z.warnings.end());
  CHECK(zero_warning->find("body <- down") != std::string::npos);
  CHECK(zero_warning->find("eyes") == std::string::npos);
  ScriptedModel far;
  far.answers["eyes"] = "About 120 cm.";
  CHECK_THROWS_WITH_AS(annotate_with_vlm(std::ref(far), kImages, "test"), doctest::Contains("eye_distance_cm = 120"), InputError);
  ScriptedModel thick;
  thick.answers["thickness"] = R"({"body": -0.5})";
  CHECK_THROWS_WITH_AS(annotate_with_vlm(std::ref(thick), kImages, "test"), doctest::Contains("regions.body.thickness_cm"), InputError);
}

TEST_CASE("regions left out are filled by the documented rules and listed") {
  PartialKnowledge p;
  p.length[size_t(Region::body)] = 2.0;
  p.length[size_t(Region::ears)] = 0.5;
  p.length[size_t(Region::tail)] = 4.0;
  p.thickness[size_t(Region::body)] = 3.0;  // thicker than long: clamped
  p.direction[size_t(Region::body)] = glm::vec3(0, 0, -1);
  std::vector<std::string> warnings;
  const Knowledge k = fill_missing_regions(p, warnings, "test");
  CHECK(k.at(Region::inner_earcanal).length_cm == doctest::Approx(0.5));  // = ears, as the prompt says
  CHECK(k.at(Region::under_tail).length_cm == doctest::Approx(4.0));      // = tail
  CHECK(k.at(Region::neck).length_cm == doctest::Approx(2.0));            // = body
  CHECK(k.at(Region::face).length_cm == doctest::Approx(2.0));            // = neck = body
  CHECK_FALSE(k.grows_fur(Region::eyes));
  CHECK_FALSE(k.grows_fur(Region::nosetip));
  CHECK_FALSE(k.grows_fur(Region::paw_pads));
  CHECK_FALSE(k.has(Region::mane));
  CHECK(k.at(Region::body).thickness_cm == doctest::Approx(2.0));
  CHECK(k.at(Region::tail).thickness_cm == doctest::Approx(0.35 * 4.0));
  CHECK(glm::distance(k.at(Region::tail).direction, glm::vec3(0, 0, -1)) < 1e-6f);
  CHECK(warnings.size() >= 4);

  PartialKnowledge none;
  none.length[size_t(Region::tail)] = 1.0;
  CHECK_THROWS_WITH_AS(fill_missing_regions(none, warnings, "test"), doctest::Contains("'body'"), InputError);
}

TEST_CASE("consensus: median lengths, mean directions, flagged disagreement") {
  std::vector<Knowledge> samples(3);
  const float lengths[3] = {1.0f, 1.2f, 5.0f};
  for (int i = 0; i < 3; ++i) {
    samples[i].eye_distance_cm = 3.0f + float(i);
    samples[i].regions[size_t(Region::body)] = RegionKnowledge{lengths[i], 0.3f, glm::normalize(glm::vec3(0.1f * float(i), -1, 0)), {}};
    samples[i].regions[size_t(Region::tail)] = RegionKnowledge{2.0f, 0.5f, glm::vec3(0, 0, -1), {}};
  }
  samples[0].regions[size_t(Region::mane)] = RegionKnowledge{9.0f, 3.0f, glm::vec3(0, -1, 0), {}};  // one in three: dropped
  const Consensus c = consensus(samples);
  CHECK(c.knowledge.at(Region::body).length_cm == doctest::Approx(1.2));
  CHECK(c.knowledge.eye_distance_cm == doctest::Approx(4.0));
  CHECK(glm::length(c.knowledge.at(Region::body).direction) == doctest::Approx(1.0));
  CHECK_FALSE(c.knowledge.has(Region::mane));
  REQUIRE(c.flagged.size() == 1);
  CHECK(c.flagged[0] == "body");
  CHECK(c.spread["body"]["length_cm"][1] == doctest::Approx(5.0));
}

namespace {
MetricScale scale_of(double eye_cm, double eye_units, std::optional<double> declared, std::optional<double> given,
                     std::optional<double> body_cm = std::nullopt, std::optional<double> body_units = std::nullopt) {
  ScaleInputs in;
  in.eye_distance_cm = eye_cm, in.eye_distance_units = eye_units, in.scene_declared = declared, in.user_given = given;
  in.body_length_cm = body_cm, in.body_length_units = body_units;
  return metric_scale(in);
}
}  // namespace

TEST_CASE("metric scale: given beats declared beats the eyes; a disagreement is a warning") {
  const MetricScale eyes = scale_of(3.2, 0.04, std::nullopt, std::nullopt);
  CHECK(eyes.source == "eyes");
  CHECK(eyes.cm_per_unit == doctest::Approx(80.0));
  CHECK(eyes.spread == doctest::Approx(kEyeCueSpread));
  const MetricScale declared = scale_of(3.2, 0.04, 100.0, std::nullopt);
  CHECK(declared.source == "scene");
  CHECK(declared.cm_per_unit == doctest::Approx(100.0));
  CHECK(declared.spread == 0);
  CHECK(*declared.disagreement == doctest::Approx(0.25));
  CHECK(declared.warning.find("25 %") != std::string::npos);
  const MetricScale given = scale_of(3.2, 0.04, 100.0, 85.0);
  CHECK(given.source == "--scene-scale");
  CHECK(given.warning.empty());  // 6 % apart
  CHECK_THROWS_WITH_AS(scale_of(3.2, 0.0, std::nullopt, std::nullopt), doctest::Contains("--scene-scale"), InputError);
}

TEST_CASE("metric scale: the eyes and the body length combine by their spreads; cues too far apart are a warning") {
  // Eyes say 80 cm per unit (spread 25 %), the body length 100 (spread 15 %): the combination lies
  // nearer the body length, in log space with weights 1/spread^2, and is surer than either.
  const MetricScale both = scale_of(3.2, 0.04, std::nullopt, std::nullopt, 46.0, 0.46);
  REQUIRE(both.cues.size() == 2);
  CHECK(both.source == "eyes + body length");
  const double we = 1 / (kEyeCueSpread * kEyeCueSpread), wb = 1 / (kBodyLengthCueSpread * kBodyLengthCueSpread);
  CHECK(both.cm_per_unit == doctest::Approx(std::exp((we * std::log(80.0) + wb * std::log(100.0)) / (we + wb))));
  CHECK(both.cm_per_unit > 90.0);
  CHECK(both.spread < kBodyLengthCueSpread);
  CHECK(both.warning.empty());  // 25 % apart: within sqrt(0.25^2 + 0.15^2) = 29 %
  // Cues that agree within their spreads: the combination's spread is the inverse-variance one.
  CHECK(both.spread == doctest::Approx(1 / std::sqrt(we + wb)));
  CHECK(both.cues_spread == doctest::Approx(both.spread));
  // The eyes say 50, half the body length's 100: beyond what the two spreads allow.
  const MetricScale apart = scale_of(3.2, 0.064, std::nullopt, std::nullopt, 46.0, 0.46);
  CHECK(apart.warning.find("differ by 50 %") != std::string::npos);
  CHECK(apart.warning.find("--scene-scale") != std::string::npos);
  // ... so the spread they report grows by the Birge ratio, |log 2| / sqrt(0.25^2 + 0.15^2) = 2.38
  // for two cues, and covers the truth whichever of them is right (spread 31 %, log 2 = 69 % apart).
  const double birge = std::log(2.0) / std::hypot(kEyeCueSpread, kBodyLengthCueSpread);
  CHECK(apart.spread == doctest::Approx(birge / std::sqrt(we + wb)));
  CHECK(apart.spread > 0.3);
  CHECK(std::fabs(std::log(apart.cm_per_unit / 100.0)) < 1.5 * apart.spread);
  CHECK(std::fabs(std::log(apart.cm_per_unit / 50.0)) < 2.5 * apart.spread);
  // A declared unit wins, and a cue 30 % off it is named.
  const MetricScale declared = scale_of(3.2, 0.032, 100.0, std::nullopt, 46.0, 0.3538);
  CHECK(declared.cm_per_unit == doctest::Approx(100.0));
  CHECK(declared.spread == 0);
  CHECK(declared.cues_spread > 0);  // the cues' own, kept for the record
  CHECK(declared.warning.find("the body length") != std::string::npos);
  CHECK(declared.warning.find("the eyes") == std::string::npos);
  // No eyes, only the body length.
  const MetricScale body = scale_of(3.2, 0.0, std::nullopt, std::nullopt, 190.0, 1.9);
  CHECK(body.source == "body length");
  CHECK(body.cm_per_unit == doctest::Approx(100.0));
}

TEST_CASE("hostile answers: mutated, deeply nested or huge, they end in a value or an InputError") {
  // Mutations of good answers (bytes flipped, cut, repeated): never a crash, never another exception.
  std::mt19937 rng(7);
  const auto good = test::good_answers();
  int readable = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    std::map<std::string, std::string> answers = good;
    for (auto& [step, text] : answers) {
      const int edits = int(rng() % 4);
      for (int e = 0; e < edits && !text.empty(); ++e) {
        const std::size_t at = rng() % text.size();
        switch (rng() % 4) {
          case 0: text[at] = char(rng() % 128); break;
          case 1: text.erase(at, rng() % 8); break;
          case 2: text.insert(at, text.substr(at, rng() % 16)); break;
          default: text.insert(at, 1, "{}[]():,'\"-.eE0"[rng() % 15]); break;
        }
      }
    }
    const ChatFunction chat = [&](const json& messages, const std::string&) { return answers[test::asked_step(messages)]; };
    try {
      const Annotation a = annotate_with_vlm(chat, kImages, "fuzz");
      ++readable;
      for (int r = 0; r < body::kRegionCount; ++r)
        if (a.knowledge.regions[size_t(r)]) {
          const RegionKnowledge& k = *a.knowledge.regions[size_t(r)];
          CHECK((k.length_cm >= 0 && k.length_cm <= kMaxLengthCm && k.thickness_cm <= k.length_cm));
          CHECK(std::fabs(glm::length(k.direction) - 1.0f) < 1e-4f);
        }
    } catch (const InputError&) {
    }
  }
  CHECK(readable > 30);  // some mutations leave every answer readable (about 1 in 40)

  // 4 MB of nested braces, quotes and digits: bounded work, no object, no crash.
  std::string deep(std::size_t(4) << 20, '{');
  for (std::size_t i = 0; i < deep.size(); i += 3) deep[i] = i % 2 ? '}' : '\'';
  CHECK(find_objects(deep).size() < 300);
  std::string digits(std::size_t(2) << 20, '7');
  CHECK_THROWS_AS(eye_distance_cm_of(digits, "eyes"), InputError);
}

TEST_CASE("the verification answer: each dict is the field named last before it; no values keeps the earlier ones") {
  ScriptedModel model;
  model.answers["verify"] = "I double-checked the length and thickness estimates.\nLength:\n{\"body\": 2.0}\nThickness:\n{\"body\": 0.7}";
  Annotation a = annotate_with_vlm(std::ref(model), kImages, "test");
  CHECK(a.knowledge.at(Region::body).length_cm == doctest::Approx(2.0));
  CHECK(a.knowledge.at(Region::body).thickness_cm == doctest::Approx(0.7));

  ScriptedModel pairs;
  pairs.answers["verify"] = "Corrected thickness and length:\n{\"body\": {\"length\": 2.2, \"thickness\": 0.6}}";
  a = annotate_with_vlm(std::ref(pairs), kImages, "test");
  CHECK(a.knowledge.at(Region::body).length_cm == doctest::Approx(2.2));
  CHECK(a.knowledge.at(Region::body).thickness_cm == doctest::Approx(0.6));

  ScriptedModel content;
  content.answers["verify"] = "Yes, I am confident the estimates are right.";
  a = annotate_with_vlm(std::ref(content), kImages, "test");
  CHECK(a.knowledge.at(Region::body).length_cm == doctest::Approx(1.0));  // the length answer's
  CHECK(a.requests == 8);  // asked once more
  CHECK(std::any_of(a.warnings.begin(), a.warnings.end(), [](const std::string& w) { return w.find("earlier ones stand") != std::string::npos; }));

  ScriptedModel no_body;
  no_body.answers["length"] = R"({"tail": 2, "ears": 1})";
  CHECK_THROWS_WITH_AS(annotate_with_vlm(std::ref(no_body), kImages, "test"), doctest::Contains("no length for 'body'"), InputError);
  CHECK(no_body.steps == std::vector<std::string>{"length", "length-retry"});
}
