#pragma once
// Sizes of a fitted body that the knowledge gives in centimetres, so their ratio is a metric scale.
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "engine/body/body_model.hpp"

namespace nf::body {

// The head-and-body length (nose tip to the tail's root, as zoologists measure an animal) of a
// model posed as `joints` (world): the polyline through its nose, muzzle, head, neck, chest,
// spine, pelvis and first tail joints, which no pose shortens. None when the model lacks one.
std::optional<double> head_and_body_length(const BodyModel& model, const std::vector<glm::dvec3>& joints);

}  // namespace nf::body
