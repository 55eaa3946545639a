#pragma once
// Which pixels of a photo show the floor, judged by the other photos. The floor is a plane with a
// known place, so a floor pixel's neighbourhood, carried to another view through the plane, looks
// the same there (unless the animal hides it in that view); a pixel of the animal, carried to the
// floor point behind it, does not look like what any view shows there. Shadows lie on the floor
// and agree too. A patch comparison (normalised cross-correlation) rather than colour, so fur of
// one colour seen at the floor point in another view does not pass for floor.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>
#include <opencv2/core.hpp>

#include "engine/io/scene.hpp"
#include "engine/prepare/scene_layout.hpp"

namespace nf::prepare {

enum FloorEvidence : std::uint8_t { kUnknown = 0, kFloor = 1, kOffFloor = 2 };

// Per pixel of camera `view` inside `region`: kFloor where at least two other views agree with its
// patch carried through the floor, kOffFloor where the patch is textured, its floor point lies
// within `reach` of `centre`, at least three views see that point and none agrees. `grey` holds
// every view's photo (CV_32F, 0-255). The rest is kUnknown (untextured patches, the wall, the sky).
cv::Mat floor_evidence(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& grey, std::size_t view,
                       const FloorPlane& floor, glm::dvec3 centre, double reach, cv::Rect region);

}  // namespace nf::prepare
