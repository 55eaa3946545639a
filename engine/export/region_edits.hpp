#pragma once
// Per-region changes to a groom that need no retraining (`nf_gpu edit`): a region's fur length
// (strands are scaled: the fur field gives each strand's shape at unit length), its hair diameter
// (the exported widths), its density (roots dropped, or added on the region's faces) and shaving (no
// roots). Regions not named keep their roots in the same order, so their strands come out
// bit-identical to the unedited groom's.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "engine/body/regions.hpp"
#include "engine/core/json.hpp"
#include "engine/defur/vertex_fur.hpp"
#include "engine/fur/roots.hpp"
#include "engine/knowledge/knowledge.hpp"

namespace nf::exporter {

struct RegionEdit {
  std::optional<double> length_cm, hair_diameter_mm, density;  // density: a factor on the region's roots
  bool shave = false;
  bool empty() const { return !length_cm && !hair_diameter_mm && !density && !shave; }
};

struct GroomEdits {
  std::array<RegionEdit, body::kRegionCount> regions;
  std::optional<std::uint32_t> strands;  // re-sample this many roots over the fur first

  // From `REGION.length_cm=X`, `REGION.hair_diameter_mm=X`, `REGION.density=X` and region names to
  // shave. UsageError naming the setting (unknown region or field, a value out of range).
  static GroomEdits parse(const std::vector<std::string>& sets, const std::vector<std::string>& shave);
  json to_json() const;
};

// The edited roots. `knowledge` gives each region's current length (the factor is length_cm over
// it); new roots for a density above 1 are drawn on the region's faces with `seed`.
fur::Roots edit_roots(const fur::Roots& roots, const GroomEdits& edits, const knowledge::Knowledge& knowledge,
                      const geometry::Mesh& bald, const fur::FaceFrames& frames, const defur::VertexFur& fur, unsigned seed);

// Each region's hair diameter (mm) after the edits: the exported strands' width at the root.
std::array<double, body::kRegionCount> region_hair_diameter_mm(const knowledge::Knowledge& knowledge, const GroomEdits& edits);

}  // namespace nf::exporter
