#pragma once
// Which pixels of a photo show the floor, judged by the other photos. The floor is a plane with a
// known place, so a floor pixel's neighbourhood, carried to another view through the plane, looks
// the same there (unless the animal hides it in that view); a pixel of the animal, carried to the
// floor point behind it, does not look like what any view shows there. Shadows lie on the floor
// and agree too. A patch comparison (normalised cross-correlation) rather than colour, so fur of
// one colour seen at the floor point in another view does not pass for floor.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <opencv2/core.hpp>

#include "engine/io/scene.hpp"
#include "engine/prepare/scene_layout.hpp"

namespace nf::prepare {

enum FloorEvidence : std::uint8_t { kUnknown = 0, kFloor = 1, kOffFloor = 2 };

// Per pixel of camera `view` inside `region`: kFloor where at least three other views agree with its
// patch carried through the floor, kOffFloor where the patch is textured, its floor point lies
// within `reach` of `centre`, at least three views see that point and none agrees. `grey` holds
// every view's photo (CV_32F, 0-255). The rest is kUnknown (untextured patches, the wall, the sky,
// and with `stride` > 1 the pixels between every stride-th one of each stride-th row).
cv::Mat floor_evidence(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& grey, std::size_t view,
                       const FloorPlane& floor, glm::dvec3 centre, double reach, cv::Rect region, int stride = 1);

// Where a view's floor evidence is looked for: the animal's box drawn into it (its bounding
// rectangle; the whole photo when the camera is inside the box), and how far from the box's foot.
cv::Rect floor_region(const io::Camera& camera, const AnimalBox& box);
inline double floor_reach(const AnimalBox& box) { return 1.5 * box.horizontal; }

// How much of the floor a view's pose puts under the animal matches the other photos' floor.
// Through a right pose most judged pixels agree (0.82-0.96 on the default suite's dog); through a
// wrong one (a photo COLMAP turned 40 degrees round the ring, or placed on the wrong copy of a floor
// pattern) the floor it reprojects is another part of the floor, and almost none agree (0.01).
// Patch correlation, so the photo's exposure does not matter.
struct FloorAgreement {
  std::size_t floor = 0, off_floor = 0;  // kFloor and kOffFloor pixels
  std::size_t pixels = 0;                // the photo's
  std::size_t judged() const { return floor + off_floor; }
  double share() const { return judged() ? double(floor) / double(judged()) : 0.0; }
};

// The views whose floor refutes their pose, ascending: at least 1 % of the photo judged, and an
// agreeing share under a third of the judged views' median, where that median is at least a half
// (in most views the floor is textured, still and flat enough to judge by). None otherwise.
std::vector<std::size_t> floor_refuted_views(const std::vector<FloorAgreement>& views);
// The views' median agreeing share (over views with 1 % judged); 0 when none is.
double median_floor_agreement(const std::vector<FloorAgreement>& views);
std::string floor_refutation_reason(const FloorAgreement& view, double median_share);

// Every view's floor agreement where no automatic mask computed it (the user's masks), from the
// cameras' photos: the evidence in floor_region on every stride-th pixel, the stride making the
// longer side about 320 judged pixels (a statistic, not a mask: photos of many megapixels cost what
// small ones do). Views count nothing when the layout has no floor.
std::vector<FloorAgreement> floor_agreement(const std::vector<io::Camera>& cameras, const SceneLayout& layout);

}  // namespace nf::prepare
