#pragma once
// Landmarks and sizes of a posed body: where its head points (the mane's border, the eyes' search),
// and the lengths the knowledge gives in centimetres, so their ratio is a metric scale.
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "engine/body/body_model.hpp"

namespace nf::body {

struct HeadAxis {
  glm::dvec3 centre;   // the head joint, world
  glm::dvec3 forward;  // towards the muzzle (unit)
};

// The head joint and the direction to the muzzle joint of a model posed as `joints` (world); none
// when the model names no "head" and "muzzle" joints (SMAL's own file names its joints otherwise).
std::optional<HeadAxis> head_axis(const BodyModel& model, const std::vector<glm::dvec3>& joints);

// The head-and-body length (nose tip to the tail's root, as zoologists measure an animal) of a
// model posed as `joints` (world): the polyline through its nose, muzzle, head, neck, chest,
// spine, pelvis and first tail joints, which no pose shortens. None when the model lacks one.
std::optional<double> head_and_body_length(const BodyModel& model, const std::vector<glm::dvec3>& joints);

}  // namespace nf::body
