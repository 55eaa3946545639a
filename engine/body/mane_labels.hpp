#pragma once
// A mane: the region the knowledge adds (preset, file or VLM) but the body template does not
// carry, labelled on a fitted surface where anatomy puts it: the neck and the head behind its
// centre, as the procedural family labels a maned animal. Whether the animal has one is the
// knowledge's call. Not from the surface's stand-off off the fit: the fit follows the fur layer, so
// a mane stands no further off it than the shoulders (docs/method.md, the defur stage).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/body/body_measures.hpp"
#include "engine/core/json.hpp"
#include "engine/geometry/mesh.hpp"

namespace nf::body {

struct ManeLabelling {
  std::uint64_t vertices = 0;  // surface vertices labelled mane
  double area_share = 0;       // their share of the surface's area
  bool head_known = false;     // false: the fit has no head axis, so only the neck became mane
};

// Labels `surface` (its regions from `fitted`, e.g. M_NeuS or M_bald) with Region::mane where its
// nearest vertex of `fitted` is on the neck, or on the face behind the head's centre. Only neck
// and face vertices of the surface change. InputError naming `source` (the fitted body's file) when
// a mesh lacks its regions.
ManeLabelling label_mane(geometry::Mesh& surface, const geometry::Mesh& fitted, const std::optional<HeadAxis>& head,
                         const std::string& source);

json to_json(const ManeLabelling& labelling);

}  // namespace nf::body
