#pragma once
// Which pixels of a photo show the floor, judged by the other photos. The floor is a plane with a
// known place, so a floor pixel's neighbourhood, carried to another view through the plane, looks
// the same there (unless the animal hides it in that view); a pixel of the animal, carried to the
// floor point behind it, does not look like what any view shows there. Shadows lie on the floor
// and agree too. A patch comparison (normalised cross-correlation) rather than colour, so fur of
// one colour seen at the floor point in another view does not pass for floor.
#include <cstdint>
#include <functional>
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
// and with `stride` > 1 the pixels between every stride-th one of each stride-th row). Views
// flagged in `left_out` (a pose found wrong) are not compared with.
// `shift` (pixels) moves the rays the view's pose casts against its photo: the pose turned by about
// shift / focal length, to judge a pose a little off as if it were right (view_floor_agreement).
cv::Mat floor_evidence(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& grey, std::size_t view,
                       const FloorPlane& floor, glm::dvec3 centre, double reach, cv::Rect region, int stride = 1,
                       const std::vector<char>* left_out = nullptr, glm::dvec2 shift = glm::dvec2(0.0));

// Where a view's floor evidence is looked for: the animal's box drawn into it (its bounding
// rectangle; the whole photo when the camera is inside the box), and how far from the box's foot.
cv::Rect floor_region(const io::Camera& camera, const AnimalBox& box);
inline double floor_reach(const AnimalBox& box) { return 1.5 * box.horizontal; }
// floor_evidence of `view` round the animal of `layout`: in floor_region, within floor_reach of
// its box's foot.
cv::Mat floor_evidence_round_animal(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& grey, const SceneLayout& layout, std::size_t view,
                                   int stride = 1, const std::vector<char>* left_out = nullptr, glm::dvec2 shift = glm::dvec2(0.0));

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

// The counts of a view's floor evidence (floor_evidence at `stride`: each pixel judged stands for
// its stride x stride block).
FloorAgreement agreement_of(const cv::Mat& evidence, int stride = 1);

// The views whose floor refutes their pose, ascending: at least 1 % of the photo judged, and an
// agreeing share under a third of the judged views' median, where that median is at least a half
// (in most views the floor is textured, still and flat enough to judge by). None otherwise.
std::vector<std::size_t> floor_refuted_views(const std::vector<FloorAgreement>& views);
// The views' median agreeing share (over views with 1 % judged); 0 when none is.
double median_floor_agreement(const std::vector<FloorAgreement>& views);
std::string floor_refutation_reason(const FloorAgreement& view, const FloorAgreement& with_slack, double median_share);

// The poses the floor refutes, one at a time. A candidate (floor_refuted_views) is judged again
// with a degree's slack (`with_slack`): COLMAP's right poses lie up to a degree off at small
// sizes (0.5 degrees is 4 px at 320 px, enough to take a fine floor's agreement to 8 %), a wrong
// one much further. A wrong view lowers the agreement of the views compared with it (a turned
// view's neighbour fell from 0.9 to 0.37), so after each refutation, the least agreeing view
// first, `find` is asked again for every view's agreement with the views `left_out` flags (which
// it neither judges nor compares with). Returns {view, reason} in ascending order of view;
// `left_out` gains them, `agreement` ends as the last finding (a view refuted keeps the agreement
// that refuted it).
struct FloorRefutation {
  std::size_t view;
  std::string reason;
};
std::vector<FloorRefutation> refute_poses_by_floor(std::vector<FloorAgreement>& agreement, std::vector<char>& left_out,
                                                   const std::function<std::vector<FloorAgreement>()>& find,
                                                   const std::function<FloorAgreement(std::size_t)>& with_slack);
// The slack a candidate is judged with again: COLMAP's right poses of the default suite's 320 px
// dog lie within 0.5 degrees (the test allows 1).
constexpr double kFloorSlackDeg = 1.0;
// One view's agreement as floor_agreement counts it. With `slack_deg` > 0, the best agreement of
// the view's pose turned by up to that much: one shift of its rays for the whole photo (a 9 x 9
// grid over +-slack, searched at twice the stride), as a pose error moves them all alike. The best
// shift per pixel instead let a 40-degree turn agree at 28-30 % on synth floors of smooth blobs,
// where the bound was 30 %: the best of 81 tries of every patch matches by chance.
FloorAgreement view_floor_agreement(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& grey, const SceneLayout& layout, std::size_t view,
                                    const std::vector<char>* left_out, double slack_deg);
// The best agreement `agreement_at(shift, stride)` gives over a 9 x 9 grid of shifts within
// +-`slack_px` (searched at twice `stride`, among shifts judging at least half the shifts' median
// of pixels; the best one counted again at `stride`); `agreement_at` may be called from several
// threads at once.
FloorAgreement best_shifted_agreement(const std::function<FloorAgreement(glm::dvec2, int)>& agreement_at, double slack_px, int stride);

// The views' photos as floor_evidence reads them (grey levels, CV_32F).
std::vector<cv::Mat> grey_photos(const std::vector<io::Camera>& cameras);
// Every view's floor agreement where no automatic mask computed it (the user's masks): the
// evidence in floor_region on every stride-th pixel, the stride making the longer side about 320
// judged pixels (a statistic, not a mask: photos of many megapixels cost what small ones do). Views
// count nothing when the layout has no floor, or when `left_out` flags them.
std::vector<FloorAgreement> floor_agreement(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& grey, const SceneLayout& layout,
                                            const std::vector<char>* left_out = nullptr);

}  // namespace nf::prepare
