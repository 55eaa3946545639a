#include "engine/export/region_edits.hpp"

#include <cmath>

#include "engine/core/error.hpp"

namespace nf::exporter {
namespace {

// A per-root number in [0, 1) from its index: which roots a density below 1 keeps, the same on
// every run.
double keep_draw(std::uint64_t i, std::int32_t region) {
  std::uint64_t x = i * 0x9E3779B97F4A7C15ull + std::uint64_t(region) * 0xBF58476D1CE4E5B9ull;
  x ^= x >> 31, x *= 0x94D049BB133111EBull, x ^= x >> 29;
  return double(x >> 11) * 0x1.0p-53;
}

void append_root(fur::Roots& out, const fur::Roots& in, std::size_t i) {
  out.face.push_back(in.face[i]), out.barycentric.push_back(in.barycentric[i]), out.position.push_back(in.position[i]);
  out.tangent.push_back(in.tangent[i]), out.bitangent.push_back(in.bitangent[i]), out.normal.push_back(in.normal[i]);
  out.direction.push_back(in.direction[i]), out.region.push_back(in.region[i]), out.length.push_back(in.length[i]);
}

}  // namespace

GroomEdits GroomEdits::parse(const std::vector<std::string>& sets, const std::vector<std::string>& shave) {
  GroomEdits e;
  const auto region_of = [](const std::string& name, const std::string& where) {
    const auto r = body::region_from_name(name);
    if (!r) {
      std::string known;
      for (std::string_view n : body::kRegionNames) known += (known.empty() ? "" : ", ") + std::string(n);
      throw UsageError(where + ": '" + name + "' is not a region (" + known + ")");
    }
    return std::size_t(*r);
  };
  for (const std::string& set : sets) {
    const std::size_t eq = set.find('='), dot = set.find('.');
    if (eq == std::string::npos || dot == std::string::npos || dot > eq)
      throw UsageError("--set " + set + ": expected REGION.FIELD=VALUE (fields: length_cm, hair_diameter_mm, density)");
    const std::string field = set.substr(dot + 1, eq - dot - 1), text = set.substr(eq + 1);
    RegionEdit& r = e.regions[region_of(set.substr(0, dot), "--set " + set)];
    double value = 0;
    try {
      std::size_t used = 0;
      value = std::stod(text, &used);
      if (used != text.size()) throw std::invalid_argument(text);
    } catch (const std::exception&) {
      throw UsageError("--set " + set + ": '" + text + "' is not a number");
    }
    const auto check = [&](double lo, double hi) {
      if (!(value >= lo && value <= hi) || !std::isfinite(value))
        throw UsageError("--set " + set + ": " + field + " must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    };
    if (field == "length_cm") check(1e-3, 1e3), r.length_cm = value;
    else if (field == "hair_diameter_mm") check(knowledge::kMinHairMm, knowledge::kMaxHairMm), r.hair_diameter_mm = value;
    else if (field == "density") check(0, 100), r.density = value;
    else if (field == "thickness_cm")  // the fur layer's depth is baked into M_bald; edit cannot change it
      throw UsageError("--set " + set + ": thickness_cm is the fur layer's depth that defurring removed; change it in WORK/knowledge/"
                       "knowledge.json and rerun `reconstruct --from defur`. The strands' width is hair_diameter_mm");
    else throw UsageError("--set " + set + ": unknown field '" + field + "' (length_cm, hair_diameter_mm, density)");
  }
  for (const std::string& name : shave) e.regions[region_of(name, "--shave")].shave = true;
  return e;
}

json GroomEdits::to_json() const {
  json out = json::object();
  json by_region = json::object();
  for (std::size_t r = 0; r < regions.size(); ++r) {
    const RegionEdit& e = regions[r];
    if (e.empty()) continue;
    json j = json::object();
    if (e.length_cm) j["length_cm"] = *e.length_cm;
    if (e.hair_diameter_mm) j["hair_diameter_mm"] = *e.hair_diameter_mm;
    if (e.density) j["density"] = *e.density;
    if (e.shave) j["shave"] = true;
    by_region[std::string(body::kRegionNames[r])] = j;
  }
  out["regions"] = by_region;
  if (strands) out["strands"] = *strands;
  return out;
}

fur::Roots edit_roots(const fur::Roots& roots, const GroomEdits& edits, const knowledge::Knowledge& knowledge,
                      const geometry::Mesh& bald, const fur::FaceFrames& frames, const defur::VertexFur& fur, unsigned seed) {
  std::array<double, body::kRegionCount> factor{};
  for (int r = 0; r < body::kRegionCount; ++r) {
    factor[std::size_t(r)] = 1.0;
    const RegionEdit& e = edits.regions[std::size_t(r)];
    if (!e.length_cm) continue;
    if (!knowledge.grows_fur(body::Region(r)))
      throw UsageError("--set " + std::string(body::kRegionNames[std::size_t(r)]) + ".length_cm: the region is bald in the knowledge, so it has no strands to lengthen");
    factor[std::size_t(r)] = *e.length_cm / double(knowledge.at(body::Region(r)).length_cm);
  }
  fur::Roots out;
  std::array<std::uint64_t, body::kRegionCount> count{};
  for (std::size_t i = 0; i < roots.size(); ++i) {
    const std::int32_t r = roots.region[i];
    const RegionEdit* e = r >= 0 && r < body::kRegionCount ? &edits.regions[std::size_t(r)] : nullptr;
    if (e) ++count[std::size_t(r)];
    if (e && (e->shave || (e->density && *e->density < 1.0 && keep_draw(i, r) >= *e->density))) continue;
    append_root(out, roots, i);
    if (e) out.length.back() = float(double(out.length.back()) * factor[std::size_t(r)]);
  }
  // Denser regions: the extra roots, drawn on the region's faces only, follow the kept ones.
  for (int r = 0; r < body::kRegionCount; ++r) {
    const RegionEdit& e = edits.regions[std::size_t(r)];
    if (e.shave || !e.density || *e.density <= 1.0 || count[std::size_t(r)] == 0) continue;
    defur::VertexFur only = fur;
    for (std::size_t v = 0; v < only.size(); ++v)
      if (only.region[v] != r) only.length[v] = 0;
    const auto extra = std::uint64_t(std::llround(double(count[std::size_t(r)]) * (*e.density - 1.0)));
    const fur::Roots added = fur::sample_roots(bald, frames, only, extra, seed + unsigned(r) * 7919u);
    for (std::size_t i = 0; i < added.size(); ++i) {
      append_root(out, added, i);
      out.region.back() = r;  // a border face may interpolate from a neighbour's vertex
      out.length.back() = float(double(out.length.back()) * factor[std::size_t(r)]);
    }
  }
  return out;
}

std::array<double, body::kRegionCount> region_hair_diameter_mm(const knowledge::Knowledge& knowledge, const GroomEdits& edits) {
  std::array<double, body::kRegionCount> t{};
  for (int r = 0; r < body::kRegionCount; ++r) {
    const RegionEdit& e = edits.regions[std::size_t(r)];
    t[std::size_t(r)] = e.hair_diameter_mm ? *e.hair_diameter_mm : double(knowledge.hair_diameter_mm_of(body::Region(r)));
  }
  return t;
}

}  // namespace nf::exporter
