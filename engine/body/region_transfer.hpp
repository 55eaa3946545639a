#pragma once
// Regions moved from a labelled mesh (the fitted body) to another surface by nearest vertex, as the
// paper moves SMAL's labels to M_NeuS; and how well a labelling agrees with a reference.
#include <array>
#include <cstdint>
#include <vector>

#include "engine/body/regions.hpp"
#include "engine/core/json.hpp"
#include "engine/geometry/mesh.hpp"

namespace nf::body {

// The region of the nearest vertex of `labelled` for every vertex of `target`.
std::vector<std::int32_t> nearest_regions(const geometry::Mesh& target, const geometry::Mesh& labelled);

struct RegionAccuracy {
  double accuracy = 0;                          // area-weighted share of the surface labelled as the reference
  std::array<double, kRegionCount> recall{};    // per reference region: share of its area labelled so (-1: absent)
  std::array<double, kRegionCount> area{};      // per reference region: its share of the surface
};

// `mesh` carries the labels to judge; the reference labels come from the nearest vertex of
// `reference` (e.g. the synthetic animal's bald body). Vertex areas are a third of the incident faces'.
// A mane is its own region: labelled where the reference has none, or missed, it counts as wrong.
RegionAccuracy region_accuracy(const geometry::Mesh& mesh, const geometry::Mesh& reference);
json to_json(const RegionAccuracy& accuracy);

}  // namespace nf::body
