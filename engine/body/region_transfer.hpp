#pragma once
// Regions moved from a labelled mesh (the fitted body) to another surface by nearest vertex, as the
// paper moves SMAL's labels to M_NeuS; and how well a labelling agrees with a reference.
#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "engine/body/body_model.hpp"
#include "engine/body/regions.hpp"
#include "engine/core/json.hpp"
#include "engine/geometry/mesh.hpp"

namespace nf::body {

// The region of the nearest vertex of `labelled` for every vertex of `target`.
std::vector<std::int32_t> nearest_regions(const geometry::Mesh& target, const geometry::Mesh& labelled);

// `fine` (a finer build of `model`'s rest surface, in its frame, with regions) attached to the
// model's rest triangles: each vertex at its closest point.
RegionDetail attach_region_detail(const BodyModel& model, const geometry::Mesh& fine);

// What labels a surface fitted by `model`: its region detail placed on `posed` (the model's
// triangles posed, e.g. BodyFit::fitted) as a point set with regions, or `posed` itself when the
// model has no detail. For nearest_regions.
geometry::Mesh region_carrier(const BodyModel& model, const geometry::Mesh& posed);

// The pads are where a paw faces the ground: the template's own rule (a paw's vertex whose normal
// lies within 53 degrees of down) applied to `mesh`'s normals, `up` the animal's up in its frame.
// Moved by nearest vertex onto a surface that lies off the template (M_NeuS over the paws' fur, the
// fitted paw grown to that envelope), the template's soles also take the paws' lower sides, which
// are fur; a vertex labelled pads that does not face down takes the region of the nearest vertex
// labelled a paw's fur or a leg. Returns how many vertices changed. Needs normals and regions.
std::size_t pads_face_down(geometry::Mesh& mesh, const glm::dvec3& up);

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
