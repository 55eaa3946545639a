#include "engine/knowledge/consensus.hpp"

#include <algorithm>
#include <map>

#include "engine/core/error.hpp"

namespace nf::knowledge {
namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

Consensus consensus(const std::vector<Knowledge>& samples) {
  NF_CHECK(!samples.empty(), "consensus of no samples");
  Consensus out;
  out.knowledge.animal = samples[0].animal;
  out.knowledge.source = samples[0].source;
  out.spread = json::object();
  std::vector<double> eyes;
  for (const Knowledge& k : samples) eyes.push_back(k.eye_distance_cm);
  out.knowledge.eye_distance_cm = float(median(eyes));
  out.spread["eye_distance_cm"] = {*std::min_element(eyes.begin(), eyes.end()), *std::max_element(eyes.begin(), eyes.end())};
  std::vector<double> hairs;
  for (const Knowledge& k : samples) hairs.push_back(k.hair_diameter_mm);
  out.knowledge.hair_diameter_mm = float(median(hairs));
  out.spread["hair_diameter_mm"] = {*std::min_element(hairs.begin(), hairs.end()), *std::max_element(hairs.begin(), hairs.end())};
  // Where values came from: what most samples say (a value the consensus took from most answers).
  std::map<std::string, std::map<std::string, std::size_t>> origins;
  for (const Knowledge& k : samples)
    for (const auto& [field, from] : k.origin) ++origins[field][from];
  for (const auto& [field, votes] : origins)
    for (const auto& [from, count] : votes)
      if (2 * count > samples.size()) out.knowledge.origin[field] = from;
  std::vector<double> bodies;
  for (const Knowledge& k : samples)
    if (k.body_length_cm) bodies.push_back(*k.body_length_cm);
  if (2 * bodies.size() > samples.size()) {  // kept when most answers give it, as a region
    out.knowledge.body_length_cm = float(median(bodies));
    out.spread["body_length_cm"] = {*std::min_element(bodies.begin(), bodies.end()), *std::max_element(bodies.begin(), bodies.end())};
  }

  for (int i = 0; i < body::kRegionCount; ++i) {
    std::vector<double> lengths, thickness, region_hairs;
    glm::dvec3 sum(0.0);
    for (const Knowledge& k : samples) {
      const auto& e = k.regions[std::size_t(i)];
      if (!e) continue;
      if (e->hair_diameter_mm) region_hairs.push_back(*e->hair_diameter_mm);
      lengths.push_back(e->length_cm);
      thickness.push_back(e->thickness_cm);
      sum += glm::dvec3(e->direction);
    }
    if (2 * lengths.size() <= samples.size()) continue;
    const std::string name(body::kRegionNames[std::size_t(i)]);
    RegionKnowledge r;
    r.length_cm = float(median(lengths));
    r.thickness_cm = std::min(r.length_cm, float(median(thickness)));
    if (2 * region_hairs.size() > lengths.size()) r.hair_diameter_mm = float(median(region_hairs));
    const double agreement = glm::length(sum) / double(lengths.size());  // 1: all answers point the same way
    if (agreement > 1e-3) r.direction = glm::vec3(glm::normalize(sum));
    else r.direction = samples[0].regions[std::size_t(i)] ? samples[0].regions[std::size_t(i)]->direction : glm::vec3(0, -1, 0);
    out.knowledge.regions[std::size_t(i)] = r;

    const auto [lo, hi] = std::minmax_element(lengths.begin(), lengths.end());
    const auto [tlo, thi] = std::minmax_element(thickness.begin(), thickness.end());
    out.spread[name] = {{"length_cm", {*lo, *hi}}, {"thickness_cm", {*tlo, *thi}}, {"direction_agreement", agreement}};
    // Directions of bald regions are copies (fill rules) and do not count.
    if ((*lo > 0 && *hi > 2.0 * *lo) || (*lo == 0 && *hi > 0) || (r.length_cm > 0 && agreement < 0.5)) out.flagged.push_back(name);
  }
  return out;
}

}  // namespace nf::knowledge
