#include "engine/knowledge/knowledge.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "engine/knowledge/presets.hpp"

namespace nf::knowledge {

using body::Region;

const RegionKnowledge& Knowledge::at(Region r) const {
  const auto& e = regions[std::size_t(r)];
  if (!e) throw InputError("knowledge for '" + animal + "': no entry for region '" + std::string(body::kRegionNames[std::size_t(r)]) + "'");
  return *e;
}

float Knowledge::hair_diameter_mm_of(Region r) const {
  const auto& e = regions[std::size_t(r)];
  return e && e->hair_diameter_mm ? *e->hair_diameter_mm : hair_diameter_mm;
}

namespace {

float finite_number(const json& j, const std::string& where, float lo, float hi) {
  if (!j.is_number()) throw InputError(where + " must be a number");
  const double v = j.get<double>();
  if (!std::isfinite(v) || v < lo || v > hi)
    throw InputError(where + " = " + std::to_string(v) + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return float(v);
}

}  // namespace

Knowledge knowledge_from_json(const json& j, const std::string& source) {
  if (!j.is_object()) throw InputError(source + ": the top level must be an object");
  Knowledge k;
  auto str = [&](const char* key, bool required) -> std::string {
    if (!j.contains(key)) {
      if (required) throw InputError(source + ": missing field '" + key + "'");
      return {};
    }
    if (!j[key].is_string()) throw InputError(source + ": field '" + std::string(key) + "' must be a string");
    return j[key].get<std::string>();
  };
  k.animal = str("animal", true);
  k.source = str("source", false);
  if (k.source.empty()) k.source = "file";
  if (!j.contains("eye_distance_cm")) throw InputError(source + ": missing field 'eye_distance_cm'");
  k.eye_distance_cm = finite_number(j["eye_distance_cm"], source + ": eye_distance_cm", 0.01f, 1000.0f);
  // Optional: files written before it existed read with the default.
  if (j.contains("hair_diameter_mm")) k.hair_diameter_mm = finite_number(j["hair_diameter_mm"], source + ": hair_diameter_mm", kMinHairMm, kMaxHairMm);
  if (j.contains("origin")) {
    if (!j["origin"].is_object()) throw InputError(source + ": 'origin' must be an object of field -> where it came from");
    for (const auto& [field, from] : j["origin"].items()) {
      if (!from.is_string()) throw InputError(source + ": origin." + field + " must be a string");
      k.origin[field] = from.get<std::string>();
    }
  }
  if (j.contains("body_length_cm") && !j["body_length_cm"].is_null())
    k.body_length_cm = finite_number(j["body_length_cm"], source + ": body_length_cm", kMinBodyLengthCm, kMaxBodyLengthCm);
  if (!j.contains("regions") || !j["regions"].is_object()) throw InputError(source + ": missing object 'regions'");
  for (const auto& [name, entry] : j["regions"].items()) {
    const std::string where = source + ": regions." + name;
    const auto region = body::region_from_name(name);
    if (!region) {
      std::vector<std::string> names(body::kRegionNames.begin(), body::kRegionNames.end());
      throw InputError(where + ": unknown region" + did_you_mean(name, names) + "; the regions: " + join(names));
    }
    if (!entry.is_object()) throw InputError(where + " must be an object");
    RegionKnowledge r;
    for (const char* key : {"length_cm", "thickness_cm", "direction"})
      if (!entry.contains(key)) throw InputError(where + ": missing field '" + key + "'");
    r.length_cm = finite_number(entry["length_cm"], where + ".length_cm", 0.0f, 500.0f);
    r.thickness_cm = finite_number(entry["thickness_cm"], where + ".thickness_cm", 0.0f, 500.0f);
    if (r.thickness_cm > r.length_cm)
      throw InputError(where + ".thickness_cm = " + std::to_string(r.thickness_cm) + " exceeds its length_cm = " +
                       std::to_string(r.length_cm) + " (the fur removed cannot be thicker than the fur is long)");
    const json& d = entry["direction"];
    if (!d.is_array() || d.size() != 3) throw InputError(where + ".direction must be an array of 3 numbers");
    for (int c = 0; c < 3; ++c) r.direction[c] = finite_number(d[c], where + ".direction[" + std::to_string(c) + "]", -1e6f, 1e6f);
    const float len = glm::length(r.direction);
    if (len > 1e-6f) r.direction /= len;
    else if (r.length_cm == 0) r.direction = {0, -1, 0};  // a bald region's "no direction": nothing grows along it
    else throw InputError(where + ".direction is the zero vector, but the region grows " + std::to_string(r.length_cm) + " cm of fur");
    if (entry.contains("hair_diameter_mm")) r.hair_diameter_mm = finite_number(entry["hair_diameter_mm"], where + ".hair_diameter_mm", kMinHairMm, kMaxHairMm);
    k.regions[std::size_t(*region)] = r;
  }
  return k;
}

json knowledge_to_json(const Knowledge& k) {
  json regions = json::object();
  for (int i = 0; i < body::kRegionCount; ++i) {
    const auto& r = k.regions[std::size_t(i)];
    if (!r) continue;
    json& e = regions[std::string(body::kRegionNames[std::size_t(i)])] = {
        {"length_cm", r->length_cm}, {"thickness_cm", r->thickness_cm}, {"direction", {r->direction.x, r->direction.y, r->direction.z}}};
    if (r->hair_diameter_mm) e["hair_diameter_mm"] = *r->hair_diameter_mm;
  }
  return {{"animal", k.animal},
          {"source", k.source},
          {"eye_distance_cm", k.eye_distance_cm},
          {"hair_diameter_mm", k.hair_diameter_mm},
          {"body_length_cm", k.body_length_cm ? json(*k.body_length_cm) : json()},
          {"origin", k.origin},
          {"regions", regions}};
}

Knowledge read_knowledge(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open the knowledge file");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {
    throw InputError(path.string() + ": not valid JSON (" + e.what() + ")");
  }
  return knowledge_from_json(j, path.string());
}

void write_knowledge(const std::filesystem::path& path, const Knowledge& k) {
  write_file_atomic(path, dump_text(knowledge_to_json(k), 2) + "\n");
}

std::string region_table(const Knowledge& k) {
  std::ostringstream out;
  char line[160];
  std::snprintf(line, sizeof line, "%-16s %10s %13s   %s\n", "region", "length cm", "thickness cm", "growth direction (x left, y up, z forward)");
  out << line;
  for (int i = 0; i < body::kRegionCount; ++i) {
    const auto& r = k.regions[std::size_t(i)];
    if (!r) continue;
    std::snprintf(line, sizeof line, "%-16s %10.2f %13.2f   [%6.2f %6.2f %6.2f]%s\n", std::string(body::kRegionNames[std::size_t(i)]).c_str(),
                  r->length_cm, r->thickness_cm, r->direction.x, r->direction.y, r->direction.z, r->length_cm > 0 ? "" : "  bald");
    out << line;
  }
  std::snprintf(line, sizeof line, "eye distance %.2f cm; a hair %.3f mm across; source %s\n", k.eye_distance_cm, k.hair_diameter_mm,
                k.source.c_str());
  out << line;
  return out.str();
}

std::vector<std::string> preset_names() {
  std::vector<std::string> names;
  for (const auto& p : embedded_presets()) names.emplace_back(p.name);
  return names;
}

Knowledge preset(const std::string& animal) {
  for (const auto& p : embedded_presets())
    if (p.name == animal) {
      const std::string name(p.name);
      Knowledge k = knowledge_from_json(json::parse(p.text), "assets/knowledge/" + name + ".json");
      k.source = "preset:" + name;
      return k;
    }
  std::string names;
  for (const auto& n : preset_names()) names += (names.empty() ? "" : ", ") + n;
  throw UsageError("no knowledge preset for '" + animal + "'; presets: " + names);
}

}  // namespace nf::knowledge
