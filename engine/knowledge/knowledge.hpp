#pragma once
// Per-region fur knowledge: length and effective thickness in cm and the growth
// direction in the animal frame, for every region, and a hair's diameter (the exported strands'
// width; the thickness is the fur layer's depth, which defurring removes). Read from knowledge.json with every field
// validated (errors name the file, the region and the field), written atomically, and available
// as built-in presets for the animals the paper annotates (assets/knowledge/, embedded at build).
#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/body/regions.hpp"
#include "engine/core/json.hpp"

namespace nf::knowledge {

// A hair's diameter when the knowledge gives none: a cat's or dog's guard hair (0.04-0.12 mm).
inline constexpr float kDefaultHairDiameterMm = 0.08f;
// A furry animal's hair is 5 um (fine underfur) to 2 mm (an elephant's); a larger answer is a
// length or the fur layer's thickness, not a hair.
inline constexpr float kMinHairMm = 0.005f, kMaxHairMm = 2.f;
// A mouse's head and body (5 cm) to an elephant's (7.5 m).
inline constexpr float kMinBodyLengthCm = 5.f, kMaxBodyLengthCm = 750.f;

struct RegionKnowledge {
  float length_cm = 0, thickness_cm = 0;
  glm::vec3 direction{0, -1, 0};  // unit, animal frame
  std::optional<float> hair_diameter_mm;  // the region's own (a mane's coarser hair); else the animal's
};

struct Knowledge {
  std::string animal;
  std::string source;  // "preset:<name>", "vlm:<model>" or "file"
  float eye_distance_cm = 0;
  float hair_diameter_mm = kDefaultHairDiameterMm;  // a hair at its root, where no region says otherwise
  // A typical adult's head-and-body length (nose tip to the tail's root), when known: a second
  // metric-scale cue beside the eyes (knowledge/metric_scale.hpp).
  std::optional<float> body_length_cm;
  // Where values came from when not from the source itself: "regions.ears.direction" -> "filled from
  // body", "eye_distance_cm" -> "preset:lion" (a VLM's unusable answer), ...
  std::map<std::string, std::string> origin;
  std::array<std::optional<RegionKnowledge>, body::kRegionCount> regions;

  // The region's entry; throws InputError naming the region when the file lacks it.
  const RegionKnowledge& at(body::Region r) const;
  bool has(body::Region r) const { return regions[std::size_t(r)].has_value(); }
  // Bald: no entry or zero length.
  bool grows_fur(body::Region r) const { return has(r) && at(r).length_cm > 0; }
  // A hair's diameter in the region (its own, else the animal's).
  float hair_diameter_mm_of(body::Region r) const;
};

Knowledge knowledge_from_json(const json& j, const std::string& source);
json knowledge_to_json(const Knowledge& k);
Knowledge read_knowledge(const std::filesystem::path& path);
void write_knowledge(const std::filesystem::path& path, const Knowledge& k);
// The regions as a table for people (what `nf_gpu annotate` prints).
std::string region_table(const Knowledge& k);

// Built-in presets: cat, dog, fox, panda, tiger, lion. Throws UsageError listing them.
Knowledge preset(const std::string& animal);
std::vector<std::string> preset_names();

}  // namespace nf::knowledge
