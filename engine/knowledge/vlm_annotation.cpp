#include "engine/knowledge/vlm_annotation.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "engine/knowledge/answer_parsing.hpp"
#include "engine/knowledge/prompts.hpp"

namespace nf::knowledge {
using body::Region;
namespace {

std::string name_of(Region r) { return std::string(body::kRegionNames[std::size_t(r)]); }

std::string lower_copy(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

const std::vector<std::string> kLengthHints{"length", "long"};
const std::vector<std::string> kThicknessHints{"thick", "subtract", "effective", "remov", "depth"};

void check_lengths(const RegionValues<double>& v, const std::string& field, const std::string& where) {
  for (const auto& [region, cm] : v.values)
    if (!(cm >= 0 && cm <= kMaxLengthCm))
      throw InputError(where + ": regions." + name_of(region) + "." + field + " = " + std::to_string(cm) +
                       " is outside 0-" + std::to_string(int(kMaxLengthCm)) + " cm");
}

void note_unknown(const std::vector<std::string>& unknown, const std::string& step, std::vector<std::string>& warnings) {
  if (!unknown.empty()) warnings.push_back("the " + step + " answer names parts that are no region, ignored: " + join(unknown));
}

// The first object of the answer that holds a table of regions for `hints`.
RegionValues<double> lengths_in(const std::vector<FoundObject>& objects, const std::vector<std::string>& hints,
                                const std::string& field, const std::string& where) {
  if (objects.empty()) throw InputError(where + ": the answer holds no dict of parts");
  std::optional<InputError> first_error;
  for (const FoundObject& o : objects) {
    try {
      RegionValues<double> v = region_lengths(o.value, hints, field, where);
      if (!v.values.empty()) {
        check_lengths(v, field, where);
        return v;
      }
    } catch (const InputError& e) {
      if (!first_error) first_error = e;
    }
  }
  throw first_error ? *first_error : InputError(where + ": the answer names no body region");
}

bool label_has(const std::string& label, const std::vector<std::string>& hints) {
  return std::any_of(hints.begin(), hints.end(), [&](const std::string& h) { return label.find(h) != std::string::npos; });
}

// The verification answer: {"length": {...}, "thickness": {...}}, per-region {"length", "thickness"}
// objects, or two dicts in the text (labelled by the words before them, else length first).
void read_verification(const std::string& text, PartialKnowledge& k, std::vector<std::string>& warnings, const std::string& where) {
  const std::vector<FoundObject> objects = find_objects(text);
  if (objects.empty()) throw InputError(where + ": the answer holds no dict of parts");
  std::optional<RegionValues<double>> lengths, thickness;
  const auto try_read = [&](const json& o, const std::vector<std::string>& hints, const std::string& field) -> std::optional<RegionValues<double>> {
    try {
      RegionValues<double> v = region_lengths(o, hints, field, where);
      if (v.values.empty()) return std::nullopt;
      check_lengths(v, field, where);
      return v;
    } catch (const InputError& e) {
      // A dict that is there but wrong is an error; one that is not about this field is not.
      if (std::string(e.what()).find("names no body region") != std::string::npos) return std::nullopt;
      throw;
    }
  };
  const auto has_key = [](const json& o, const std::vector<std::string>& hints) {
    for (const auto& [key, value] : o.items())
      if (value.is_object() && label_has(lower_copy(key), hints)) return true;
    return false;
  };
  for (const FoundObject& o : objects)
    if (has_key(o.value, kLengthHints) || has_key(o.value, kThicknessHints)) {
      if (has_key(o.value, kLengthHints)) lengths = try_read(o.value, kLengthHints, "length_cm");
      if (has_key(o.value, kThicknessHints)) thickness = try_read(o.value, kThicknessHints, "thickness_cm");
      break;
    }
  if (!lengths && !thickness) {
    std::vector<const FoundObject*> unlabelled;
    for (const FoundObject& o : objects) {
      if (label_has(o.label, kThicknessHints) && !thickness) thickness = try_read(o.value, kThicknessHints, "thickness_cm");
      else if (label_has(o.label, kLengthHints) && !lengths) lengths = try_read(o.value, kLengthHints, "length_cm");
      else unlabelled.push_back(&o);
    }
    for (const FoundObject* o : unlabelled) {  // per-region {"length", "thickness"}, or by order
      if (!lengths) lengths = try_read(o->value, kLengthHints, "length_cm");
      else if (!thickness) thickness = try_read(o->value, kThicknessHints, "thickness_cm");
    }
    if (objects.size() == 1 && lengths && !thickness) {
      // One dict of per-region objects carries both fields.
      try {
        thickness = try_read(objects[0].value, kThicknessHints, "thickness_cm");
      } catch (const InputError&) {
      }
    }
  }
  if (!lengths && !thickness) throw InputError(where + ": the answer holds no dict of lengths or thicknesses");
  if (lengths) {
    note_unknown(lengths->unknown, "verification", warnings);
    for (const auto& [r, cm] : lengths->values) k.length[std::size_t(r)] = cm;
  }
  if (thickness)
    for (const auto& [r, cm] : thickness->values) k.thickness[std::size_t(r)] = cm;
}

}  // namespace

Annotation annotate_with_vlm(const ChatFunction& chat, const AnnotationImages& images, const std::string& where) {
  Annotation out;
  PartialKnowledge k;
  std::optional<double> eye_cm;
  json messages = json::array({{{"role", "system"}, {"content", system_prompt()}}});
  bool first = true;
  for (const Prompt& prompt : paper_prompts()) {
    json content = prompt.message();
    if (first) {  // the photos come with the first question, as the paper sends them
      content = json::array({{{"type", "image_url"}, {"image_url", {{"url", images.frontal}}}},
                             {{"type", "image_url"}, {"image_url", {{"url", images.side_with_axes}}}},
                             {{"type", "text"}, {"text", prompt.message()}}});
      first = false;
    }
    messages.push_back({{"role", "user"}, {"content", content}});
    const std::string at = where + ": the answer to the " + prompt.step + " prompt";
    for (int attempt = 0;; ++attempt) {
      const std::string answer = chat(messages, attempt == 0 ? prompt.step : prompt.step + "-retry");
      ++out.requests;
      messages.push_back({{"role", "assistant"}, {"content", answer}});
      try {
        if (answer.find_first_not_of(" \t\r\n") == std::string::npos) throw InputError(at + ": the answer is empty");
        if (prompt.step == "length") {
          const RegionValues<double> v = lengths_in(find_objects(answer), kLengthHints, "length_cm", at);
          note_unknown(v.unknown, "length", out.warnings);
          for (const auto& [r, cm] : v.values) k.length[std::size_t(r)] = cm;
        } else if (prompt.step == "thickness") {
          const RegionValues<double> v = lengths_in(find_objects(answer), kThicknessHints, "thickness_cm", at);
          note_unknown(v.unknown, "thickness", out.warnings);
          for (const auto& [r, cm] : v.values) k.thickness[std::size_t(r)] = cm;
        } else if (prompt.step == "verify") {
          read_verification(answer, k, out.warnings, at);
        } else if (prompt.step == "direction") {
          const std::vector<FoundObject> objects = find_objects(answer);
          if (objects.empty()) throw InputError(at + ": the answer holds no dict of parts");
          std::optional<RegionValues<glm::vec3>> v;
          for (const FoundObject& o : objects) {
            try {
              v = region_directions(o.value, at);
              break;
            } catch (const InputError& e) {
              if (std::string(e.what()).find("names no body region") == std::string::npos) throw;
            }
          }
          if (!v) throw InputError(at + ": the answer names no body region");
          note_unknown(v->unknown, "direction", out.warnings);
          for (const auto& [r, d] : v->values) k.direction[std::size_t(r)] = d;
        } else {
          const double cm = eye_distance_cm_of(answer, at);
          if (!(cm >= kMinEyeCm && cm <= kMaxEyeCm))
            throw InputError(at + ": eye_distance_cm = " + std::to_string(cm) + " is outside " + std::to_string(kMinEyeCm).substr(0, 3) +
                             "-" + std::to_string(int(kMaxEyeCm)) + " cm");
          eye_cm = cm;
        }
        break;
      } catch (const InputError& e) {
        if (attempt > 0) throw;
        const std::string problem = std::string(e.what()).substr(at.size() + 2);
        out.warnings.push_back("the " + prompt.step + " answer was asked again: " + problem);
        messages.push_back({{"role", "user"}, {"content", repair_prompt(problem, prompt)}});
      }
    }
  }
  out.knowledge = fill_missing_regions(k, out.warnings, where);
  out.knowledge.eye_distance_cm = float(*eye_cm);
  return out;
}

Knowledge fill_missing_regions(const PartialKnowledge& a, std::vector<std::string>& warnings, const std::string& where) {
  // Where a missing region takes its values from (README, *Knowledge*).
  const auto source_of = [](Region r) -> std::optional<Region> {
    switch (r) {
      case Region::inner_earcanal: return Region::ears;
      case Region::front_paws: return Region::paws;
      case Region::paws: return Region::front_paws;
      case Region::leg_front: return Region::leg_rear;
      case Region::leg_rear: return Region::leg_front;
      case Region::under_tail: return Region::tail;
      case Region::face: return Region::neck;
      case Region::body: return std::nullopt;
      default: return Region::body;
    }
  };
  const auto bald_when_missing = [](Region r) { return r == Region::eyes || r == Region::nosetip || r == Region::paw_pads; };
  const auto idx = [](Region r) { return std::size_t(r); };
  if (!a.length[idx(Region::body)])
    throw InputError(where + ": the answers give no fur length for 'body', the region every other one falls back on");

  // The region whose answer stands in for r: r itself, else along the fill rules (no cycles).
  const auto donor = [&](Region r, const auto& field) -> std::optional<Region> {
    Region at = r;
    for (int hops = 0; hops < 4; ++hops) {
      if (field[idx(at)]) return at;
      const std::optional<Region> next = source_of(at);
      if (!next || *next == r) break;
      at = *next;
    }
    return field[idx(Region::body)] ? std::optional<Region>(Region::body) : std::nullopt;
  };

  Knowledge k;
  std::vector<std::string> filled, bald, no_thickness, no_direction;
  for (int i = 0; i < body::kRegionCount; ++i) {
    const Region r = Region(i);
    const std::string name = name_of(r);
    if (r == Region::mane && !a.length[idx(r)]) continue;  // no mane unless the answer has one
    RegionKnowledge e;
    std::optional<Region> length_from;  // the region whose length this one took
    if (a.length[idx(r)]) {
      e.length_cm = float(*a.length[idx(r)]);
    } else if (bald_when_missing(r)) {
      e.length_cm = 0;
      bald.push_back(name);
    } else {
      length_from = *donor(r, a.length);
      e.length_cm = float(*a.length[idx(*length_from)]);
      filled.push_back(name + " <- " + name_of(*length_from));
    }
    if (a.thickness[idx(r)]) {
      e.thickness_cm = float(*a.thickness[idx(r)]);
    } else if (e.length_cm == 0) {
      e.thickness_cm = 0;
    } else if (length_from && a.thickness[idx(*length_from)]) {  // the fur it copies, whole
      e.thickness_cm = float(*a.thickness[idx(*length_from)]);
    } else {
      e.thickness_cm = 0.35f * e.length_cm;
      no_thickness.push_back(name);
    }
    if (e.thickness_cm > e.length_cm) {
      warnings.push_back("regions." + name + ".thickness_cm " + std::to_string(e.thickness_cm) + " exceeds its length " +
                         std::to_string(e.length_cm) + " cm: set to the length");
      e.thickness_cm = e.length_cm;
    }
    if (a.direction[idx(r)]) {
      e.direction = *a.direction[idx(r)];
    } else if (const auto from = donor(r, a.direction)) {
      e.direction = *a.direction[idx(*from)];
      if (e.length_cm > 0) no_direction.push_back(name + " <- " + name_of(*from));
    } else {
      e.direction = {0, -1, 0};  // fur falls with gravity when nothing says otherwise
      if (e.length_cm > 0) no_direction.push_back(name + " <- down");
    }
    k.regions[idx(r)] = e;
  }
  if (!filled.empty()) warnings.push_back("no length in the answers for " + join(filled, "; ") + " (filled as shown)");
  if (!bald.empty()) warnings.push_back("no length in the answers for " + join(bald) + ": bald");
  if (!no_thickness.empty()) warnings.push_back("no thickness in the answers for " + join(no_thickness) + ": 0.35 x length");
  if (!no_direction.empty()) warnings.push_back("no direction in the answers for " + join(no_direction, "; ") + " (filled as shown)");
  return k;
}

}  // namespace nf::knowledge
