#include "engine/knowledge/vlm_annotation.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "engine/knowledge/answer_parsing.hpp"
#include "engine/knowledge/prompts.hpp"

namespace nf::knowledge {
using body::Region;
namespace {

std::string name_of(Region r) { return std::string(body::kRegionNames[std::size_t(r)]); }


const std::vector<std::string> kLengthHints{"length", "long"};
const std::vector<std::string> kThicknessHints{"thick", "subtract", "effective", "remov", "depth"};

// A number as people write it: 75, 0.35, 1e+300.
std::string num(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

void check_lengths(const RegionValues<double>& v, const std::string& field, const std::string& where) {
  for (const auto& [region, cm] : v.values)
    if (!(cm >= 0 && cm <= kMaxLengthCm))
      throw InputError(where + ": regions." + name_of(region) + "." + field + " = " + num(cm) + " is outside 0-" +
                       num(kMaxLengthCm) + " cm");
}

void note_unknown(const std::vector<std::string>& unknown, const std::string& step, std::vector<std::string>& warnings) {
  if (!unknown.empty()) warnings.push_back("the " + step + " answer names parts that are no region, ignored: " + join(unknown));
}

// Which field the words before a dict announce: the one named last ("I checked the length and
// thickness. Length: {...}" announces lengths). 'L', 'T' or 0.
char announced(const std::string& label) {
  std::size_t l = std::string::npos, t = std::string::npos;
  for (const std::string& h : kLengthHints)
    if (const std::size_t at = label.rfind(h); at != std::string::npos && (l == std::string::npos || at > l)) l = at;
  for (const std::string& h : kThicknessHints)
    if (const std::size_t at = label.rfind(h); at != std::string::npos && (t == std::string::npos || at > t)) t = at;
  if (l == std::string::npos && t == std::string::npos) return 0;
  if (t == std::string::npos) return 'L';
  if (l == std::string::npos) return 'T';
  return l > t ? 'L' : 'T';
}

// The table of `field` in one dict, or nullopt when the dict holds none; a dict that has one but
// with a bad value is an error naming it.
std::optional<RegionValues<double>> read_table(const json& o, char field, const std::string& where) {
  const bool lengths = field == 'L';
  try {
    RegionValues<double> v = region_lengths(o, lengths ? kLengthHints : kThicknessHints, lengths ? kThicknessHints : kLengthHints,
                                            lengths ? "length_cm" : "thickness_cm", where);
    if (v.values.empty()) return std::nullopt;
    check_lengths(v, lengths ? "length_cm" : "thickness_cm", where);
    return v;
  } catch (const InputError& e) {
    if (std::string(e.what()).find("names no body region") != std::string::npos) return std::nullopt;
    throw;
  }
}

// The dict of the answer that holds `field`: the one announced for it, else the first not announced
// for the other field, else the first that reads.
RegionValues<double> table_in(const std::vector<FoundObject>& objects, char field, const std::string& where) {
  if (objects.empty()) throw InputError(where + ": the answer holds no dict of parts");
  const char other = field == 'L' ? 'T' : 'L';
  for (int pass = 0; pass < 3; ++pass)
    for (const FoundObject& o : objects) {
      const char a = announced(o.label);
      if ((pass == 0 && a != field) || (pass == 1 && a == other)) continue;
      if (std::optional<RegionValues<double>> v = read_table(o.value, field, where)) return *v;
    }
  throw InputError(where + ": the answer names no body region");
}

bool has_wrapper(const json& o, const std::vector<std::string>& hints) {
  for (const auto& [key, value] : o.items()) {
    if (!value.is_object()) continue;
    const std::string k = to_lower(key);
    if (std::any_of(hints.begin(), hints.end(), [&](const std::string& h) { return k.find(h) != std::string::npos; })) return true;
  }
  return false;
}

// The verification answer: {"length": {...}, "thickness": {...}}, per-region {"length", "thickness"}
// pairs, or two dicts in the text (each the field the words before it name last, else in order:
// lengths first). Returns false when it holds no dict at all.
bool read_verification(const std::string& text, PartialKnowledge& k, std::vector<std::string>& warnings, const std::string& where) {
  const std::vector<FoundObject> objects = find_objects(text);
  if (objects.empty()) return false;
  std::optional<RegionValues<double>> lengths, thickness;
  for (const FoundObject& o : objects)
    if (has_wrapper(o.value, kLengthHints) || has_wrapper(o.value, kThicknessHints)) {  // one dict of two
      lengths = read_table(o.value, 'L', where), thickness = read_table(o.value, 'T', where);
      break;
    }
  if (!lengths && !thickness && objects.size() == 1) {  // one dict: per-region pairs carry both, else its label
    lengths = read_table(objects[0].value, 'L', where);
    thickness = read_table(objects[0].value, 'T', where);
    if (lengths && thickness && lengths->values == thickness->values) {  // plain numbers: one field only
      (announced(objects[0].label) == 'T' ? lengths : thickness).reset();
    }
  } else if (!lengths && !thickness) {
    std::vector<const FoundObject*> unannounced;
    for (const FoundObject& o : objects) {
      const char a = announced(o.label);
      if (a == 'L' && !lengths) lengths = read_table(o.value, 'L', where);
      else if (a == 'T' && !thickness) thickness = read_table(o.value, 'T', where);
      else if (a == 0) unannounced.push_back(&o);
    }
    for (const FoundObject* o : unannounced) {
      if (!lengths) lengths = read_table(o->value, 'L', where);
      else if (!thickness) thickness = read_table(o->value, 'T', where);
    }
  }
  if (!lengths && !thickness) throw InputError(where + ": the answer holds no dict of lengths or thicknesses");
  if (lengths) {
    note_unknown(lengths->unknown, "verification", warnings);
    for (const auto& [r, cm] : lengths->values) k.length[std::size_t(r)] = cm;
  }
  if (thickness)
    for (const auto& [r, cm] : thickness->values) k.thickness[std::size_t(r)] = cm;
  return true;
}

bool is_table_step(const std::string& step) { return step == "length" || step == "thickness" || step == "direction"; }

// One answer to the length, thickness or direction prompt into `k`. Throws InputError naming the
// region and field of the first value it refuses; a length answer must give `body` unless
// `body_given` (the fallback gives it).
void read_table_step(const std::string& step, const std::vector<FoundObject>& objects, PartialKnowledge& k,
                     std::vector<std::string>& warnings, const std::string& at, bool body_given = false) {
  if (step == "length" || step == "thickness") {
    const RegionValues<double> v = table_in(objects, step == "length" ? 'L' : 'T', at);
    if (step == "length" && !body_given && std::none_of(v.values.begin(), v.values.end(), [](const auto& e) { return e.first == Region::body; }))
      throw InputError(at + ": no length for 'body', the region every other one falls back on");
    note_unknown(v.unknown, step, warnings);
    for (const auto& [r, cm] : v.values) (step == "length" ? k.length : k.thickness)[std::size_t(r)] = cm;
    return;
  }
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
  note_unknown(v->unknown, "direction", warnings);
  for (const auto& [r, d] : v->values) k.direction[std::size_t(r)] = d;
}

// The region an error message names ("...: regions.body.length_cm = 75"), if any.
std::optional<Region> region_named_in(const std::string& message) {
  const std::size_t at = message.find("regions.");
  if (at == std::string::npos) return std::nullopt;
  const std::size_t begin = at + 8, end = message.find_first_of(".: ", begin);
  return body::region_from_name(message.substr(begin, end == std::string::npos ? std::string::npos : end - begin));
}

// Every key that names `r`, at any depth.
void erase_region(json& j, Region r) {
  if (!j.is_object()) return;
  for (auto it = j.begin(); it != j.end();) {
    if (match_region(it.key()) == r) {
      it = j.erase(it);
    } else {
      erase_region(*it, r);
      ++it;
    }
  }
}

const char* field_of(const std::string& step) {
  return step == "length" ? "length_cm" : step == "thickness" ? "thickness_cm" : "direction";
}

// After the retry: the regions whose values still do not read take the fallback's (the animal's
// preset), the rest of the answer stands; an answer with nothing readable gives way to the
// fallback for the whole field. Each replaced value is a warning and an entry of `origin`.
void fall_back_on_table(const std::string& step, const std::string& answer, const std::string& problem, const Knowledge& fallback,
                        PartialKnowledge& k, Annotation& out, const std::string& at) {
  std::vector<FoundObject> objects = find_objects(answer);
  std::vector<Region> refused;
  std::optional<std::string> whole;  // why nothing of the answer reads
  for (std::string message = problem;;) {
    const std::optional<Region> r = region_named_in(message);
    if (!r || std::find(refused.begin(), refused.end(), *r) != refused.end()) {
      whole = message;
      break;
    }
    refused.push_back(*r);
    for (FoundObject& o : objects) erase_region(o.value, *r);
    try {
      PartialKnowledge attempt = k;
      const bool body_refused = std::find(refused.begin(), refused.end(), Region::body) != refused.end();
      read_table_step(step, objects, attempt, out.warnings, at, body_refused && fallback.has(Region::body));
      k = attempt;
      break;
    } catch (const InputError& e) {
      message = e.what();
    }
  }
  const std::string field = field_of(step);
  const auto take = [&](Region r) {
    if (!fallback.has(r)) return false;
    const RegionKnowledge& f = fallback.at(r);
    if (step == "length") k.length[std::size_t(r)] = f.length_cm;
    else if (step == "thickness") k.thickness[std::size_t(r)] = f.thickness_cm;
    else k.direction[std::size_t(r)] = f.direction;
    out.origin["regions." + name_of(r) + "." + field] = fallback.source;
    return true;
  };
  if (whole) {
    for (int i = 0; i < body::kRegionCount; ++i) take(Region(i));
    out.warnings.push_back("the " + step + " answers stayed unusable (" + *whole + "): the " + fallback.source + " values stand for " +
                           field + " in every region");
    return;
  }
  for (Region r : refused) {
    const bool taken = take(r);
    out.warnings.push_back("regions." + name_of(r) + "." + field + ": the answers stayed unusable; " +
                           (taken ? "the " + fallback.source + " value stands" : "the fill rules decide"));
  }
}
}  // namespace

Annotation annotate_with_vlm(const ChatFunction& chat, const AnnotationImages& images, const std::string& where,
                             const Knowledge* fallback) {
  Annotation out;
  PartialKnowledge k;
  std::optional<double> eye_cm, body_cm;
  double hair_mm = kDefaultHairDiameterMm;
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
        if (is_table_step(prompt.step)) {
          read_table_step(prompt.step, find_objects(answer), k, out.warnings, at);
        } else if (prompt.step == "verify") {
          // This step only corrects: an answer without any dict ("yes, they are right") after the
          // retry keeps the earlier values.
          if (!read_verification(answer, k, out.warnings, at)) {
            if (attempt == 0) throw InputError(at + ": the answer holds no dict of parts");
            out.warnings.push_back("the verify answer gave no values; the earlier ones stand");
          }
        } else if (prompt.step == "hair") {
          const double mm = hair_diameter_mm_of(answer, at);
          if (!(mm >= kMinHairMm && mm <= kMaxHairMm))
            throw InputError(at + ": hair_diameter_mm = " + num(mm) + " is outside " + num(kMinHairMm) + "-" + num(kMaxHairMm) + " mm");
          hair_mm = mm;
        } else if (prompt.step == "body") {
          const double cm = body_length_cm_of(answer, at);
          if (!(cm >= kMinBodyLengthCm && cm <= kMaxBodyLengthCm))
            throw InputError(at + ": body_length_cm = " + num(cm) + " is outside " + num(kMinBodyLengthCm) + "-" + num(kMaxBodyLengthCm) + " cm");
          body_cm = cm;
        } else {
          const double cm = eye_distance_cm_of(answer, at);
          if (!(cm >= kMinEyeCm && cm <= kMaxEyeCm))
            throw InputError(at + ": eye_distance_cm = " + num(cm) + " is outside " + num(kMinEyeCm) + "-" + num(kMaxEyeCm) + " cm");
          eye_cm = cm;
        }
        break;
      } catch (const InputError& e) {
        if (attempt > 0 && prompt.step == "hair") {  // only the export's widths hang on it
          out.warnings.push_back("no usable hair diameter in the answers (" + std::string(e.what()) + "): " + num(kDefaultHairDiameterMm) + " mm");
          break;
        }
        if (attempt > 0 && prompt.step == "body") {  // one of the scale's cues; the eyes remain
          out.warnings.push_back("no usable head-and-body length in the answers (" + std::string(e.what()) +
                                 "): the metric scale rests on the eyes");
          break;
        }
        if (attempt > 0 && fallback && is_table_step(prompt.step)) {
          fall_back_on_table(prompt.step, answer, e.what(), *fallback, k, out, at);
          break;
        }
        if (attempt > 0 && fallback && prompt.step == "verify") {  // it only corrects: what stood before stands
          out.warnings.push_back("the verify answer stayed unusable (" + std::string(e.what()) + "): the earlier values stand");
          break;
        }
        if (attempt > 0 && fallback && prompt.step == "eyes") {
          eye_cm = fallback->eye_distance_cm;
          out.warnings.push_back("the eyes answer stayed unusable (" + std::string(e.what()) + "): the " + fallback->source +
                                 " eye distance, " + num(fallback->eye_distance_cm) + " cm, stands");
          out.origin["eye_distance_cm"] = fallback->source;
          break;
        }
        if (attempt > 0) throw;
        const std::string message = e.what();
        const std::string problem = message.rfind(at + ": ", 0) == 0 ? message.substr(at.size() + 2) : message;
        out.warnings.push_back("the " + prompt.step + " answer was asked again: " + problem);
        messages.push_back({{"role", "user"}, {"content", repair_prompt(problem, prompt)}});
      }
    }
  }
  out.knowledge = fill_missing_regions(k, out.warnings, where);
  for (const auto& [field, source] : out.origin) out.knowledge.origin[field] = source;
  out.knowledge.eye_distance_cm = float(*eye_cm);
  out.knowledge.hair_diameter_mm = float(hair_mm);
  if (body_cm) out.knowledge.body_length_cm = float(*body_cm);
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
      k.origin["regions." + name + ".length_cm"] = "bald: no answer";
    } else {
      length_from = *donor(r, a.length);
      e.length_cm = float(*a.length[idx(*length_from)]);
      filled.push_back(name + " <- " + name_of(*length_from));
      k.origin["regions." + name + ".length_cm"] = "filled from " + name_of(*length_from);
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
      k.origin["regions." + name + ".thickness_cm"] = "0.35 x length";
    }
    if (e.thickness_cm > e.length_cm) {
      warnings.push_back("regions." + name + ".thickness_cm " + num(e.thickness_cm) + " exceeds its length " +
                         num(e.length_cm) + " cm: set to the length");
      e.thickness_cm = e.length_cm;
    }
    if (a.direction[idx(r)]) {
      e.direction = *a.direction[idx(r)];
    } else if (const auto from = donor(r, a.direction)) {
      e.direction = *a.direction[idx(*from)];
      if (e.length_cm > 0) no_direction.push_back(name + " <- " + name_of(*from));
      if (e.length_cm > 0) k.origin["regions." + name + ".direction"] = "filled from " + name_of(*from);
    } else {
      e.direction = {0, -1, 0};  // fur falls with gravity when nothing says otherwise
      if (e.length_cm > 0) no_direction.push_back(name + " <- down");
      if (e.length_cm > 0) k.origin["regions." + name + ".direction"] = "down: no answer";
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
