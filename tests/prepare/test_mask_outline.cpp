// prepare's outline refinement (mask_outline.hpp) on a photo made here: a furry blob (a tufted
// outline, striped fur) on a textured floor, 4 x 4 samples a pixel, its true mask the pixels at
// least half covered. A mask cut as GrabCut cuts (tufts cut off and gaps filled by its smoothness,
// the outline a pixel off) is moved back onto the true outline; a background-coloured patch inside
// the animal, away from the outline, stays animal; an animal in the floor's colours (its own
// pattern) is cut no worse; where one flat colour leaves nothing to follow, nothing moves.
#include <doctest/doctest.h>

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "engine/core/error.hpp"
#include "engine/prepare/mask_outline.hpp"

using namespace nf;

namespace {

constexpr int kSize = 200;
constexpr double kPi = 3.14159265358979323846;

double hash01(int i, int j, unsigned seed) {
  std::uint64_t x = std::uint64_t(std::int64_t(i)) * 0x9E3779B97F4A7C15ULL ^ std::uint64_t(std::int64_t(j)) * 0xC2B2AE3D27D4EB4FULL ^ seed;
  x ^= x >> 31, x *= 0xBF58476D1CE4E5B9ULL, x ^= x >> 29;
  return double(x >> 11) / double(1ULL << 53);
}

double noise(double u, double v, double cell, unsigned seed) {
  const double x = u / cell, y = v / cell, fx = x - std::floor(x), fy = y - std::floor(y);
  const int i = int(std::floor(x)), j = int(std::floor(y));
  return (1 - fy) * ((1 - fx) * hash01(i, j, seed) + fx * hash01(i + 1, j, seed)) + fy * ((1 - fx) * hash01(i, j + 1, seed) + fx * hash01(i + 1, j + 1, seed));
}

// Whether (x, y) lies on the animal: an ellipse whose radius is ruffled by tufts.
bool on_animal(double x, double y) {
  const double dx = (x - 100) / 62, dy = (y - 104) / 44, angle = std::atan2(dy, dx);
  const double tufts = 0.07 * std::sin(23 * angle) + 0.04 * std::sin(41 * angle + 1.0);
  return std::hypot(dx, dy) < 1 + tufts;
}

struct Scene {
  cv::Mat photo, truth;  // BGR 8-bit; 255 where at least half of a pixel is animal
};

enum class Coat { tan, floor_palette, flat };

// `tan`: a striped tan coat; `floor_palette`: the floor's colours in a pattern of the animal's own
// (a grey dog on grey stone); `flat`: the animal and the floor one flat colour (nothing to follow).
Scene make_scene(Coat coat) {
  Scene s{cv::Mat(kSize, kSize, CV_8UC3), cv::Mat(kSize, kSize, CV_8U)};
  const auto mottled = [](double x, double y, unsigned seed) {
    const double t = noise(x, y, 9, seed), u = noise(x, y, 4, seed + 1);
    return cv::Vec3d(60 + 120 * t + 40 * u, 90 + 100 * t, 70 + 60 * u + 60 * t);  // B, G, R: a greenish, mottled floor
  };
  const auto floor = [&](double x, double y) { return coat == Coat::flat ? cv::Vec3d(90, 120, 110) : mottled(x, y, 1); };
  const auto fur = [&](double x, double y) {
    if (coat == Coat::flat) return floor(x, y);
    if (coat == Coat::floor_palette) return mottled(x + 1000, y, 7);
    // Strands along the body: stripes across x, shaded by a coarser noise; a tan coat.
    const double stripe = 0.5 + 0.5 * std::sin(2 * kPi * (y + 6 * noise(x, y, 15, 3)) / 3.0), shade = 0.6 + 0.4 * noise(x, y, 20, 4);
    return cv::Vec3d(40 + 30 * stripe, 110 + 60 * stripe, 170 + 70 * stripe) * shade;
  };
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      cv::Vec3d sum(0, 0, 0);
      int covered = 0;
      for (int sy = 0; sy < 4; ++sy)
        for (int sx = 0; sx < 4; ++sx) {
          const double px = x + (sx + 0.5) / 4, py = y + (sy + 0.5) / 4;
          const bool animal = on_animal(px, py);
          covered += animal;
          sum += animal ? fur(px, py) : floor(px, py);
        }
      for (int c = 0; c < 3; ++c) s.photo.at<cv::Vec3b>(y, x)[c] = cv::saturate_cast<std::uint8_t>(sum[c] / 16);
      s.truth.at<std::uint8_t>(y, x) = covered >= 8 ? 255 : 0;
    }
  return s;
}

// What GrabCut's smoothness makes of an outline: tufts cut off, the gaps between them filled, and
// the whole a pixel wider on one side and narrower on the other.
cv::Mat cut_like_grabcut(const cv::Mat& truth) {
  const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(7, 7));
  cv::Mat smooth, shifted;
  cv::morphologyEx(truth, smooth, cv::MORPH_OPEN, disc);
  cv::morphologyEx(smooth, smooth, cv::MORPH_CLOSE, disc);
  const cv::Mat move = (cv::Mat_<double>(2, 3) << 1, 0, 1, 0, 1, 0);  // a pixel to the right
  cv::warpAffine(smooth, shifted, move, smooth.size(), cv::INTER_NEAREST);
  return shifted;
}

double iou(const cv::Mat& a, const cv::Mat& b) { return double(cv::countNonZero(a & b)) / double(cv::countNonZero(a | b)); }

}  // namespace

TEST_CASE("mask outline: a GrabCut-like outline moves back onto the animal's true outline") {
  const Scene s = make_scene(Coat::tan);
  const cv::Mat cut = cut_like_grabcut(s.truth);
  const cv::Mat snapped = prepare::snap_outline_to_photo(s.photo, cut);
  const double before = iou(cut, s.truth), after = iou(snapped, s.truth);
  MESSAGE("IoU with the true mask: the cut ", before, ", its outline snapped ", after);
  CHECK(before < 0.96);
  CHECK(after > before + 0.02);
  CHECK(after > 0.96);
  // Nothing beyond the band round the cut's outline moved.
  cv::Mat grown, shrunk;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
  cv::dilate(cut, grown, kernel, cv::Point(-1, -1), 3);  // the band at 200 px
  cv::erode(cut, shrunk, kernel, cv::Point(-1, -1), 3);
  CHECK(cv::countNonZero(snapped & (grown == 0)) == 0);
  CHECK(cv::countNonZero(shrunk & (snapped == 0)) == 0);
}

TEST_CASE("mask outline: a patch of the floor's colours inside the animal stays animal; an empty mask stays empty") {
  Scene s = make_scene(Coat::tan);
  // A floor-coloured spot (8 px across) well inside the body: the cut holds it, as it should.
  for (int y = 100; y < 108; ++y)
    for (int x = 96; x < 104; ++x) s.photo.at<cv::Vec3b>(y, x) = make_scene(Coat::flat).photo.at<cv::Vec3b>(y, x);
  const cv::Mat snapped = prepare::snap_outline_to_photo(s.photo, s.truth);
  CHECK(cv::countNonZero(snapped(cv::Rect(96, 100, 8, 8))) == 64);
  CHECK(iou(snapped, s.truth) > 0.97);  // the right outline stays right
  const cv::Mat empty = cv::Mat::zeros(kSize, kSize, CV_8U);
  CHECK(cv::countNonZero(prepare::snap_outline_to_photo(s.photo, empty)) == 0);
  CHECK_THROWS_AS(prepare::snap_outline_to_photo(s.truth, s.truth), InputError);  // not a colour photo
}

TEST_CASE("mask outline: an animal in the floor's colours is cut no worse; with nothing to follow the cut stands") {
  // The floor's palette in the animal's own pattern: the outline is where the pattern changes.
  const Scene grey = make_scene(Coat::floor_palette);
  const cv::Mat cut = cut_like_grabcut(grey.truth);
  const cv::Mat snapped = prepare::snap_outline_to_photo(grey.photo, cut);
  MESSAGE("in the floor's colours, IoU with the truth: the cut ", iou(cut, grey.truth), ", snapped ", iou(snapped, grey.truth));
  CHECK(iou(snapped, grey.truth) > iou(cut, grey.truth) - 0.005);
  // One flat colour everywhere: no window separates the two sides, and no pixel moves.
  const Scene flat = make_scene(Coat::flat);
  CHECK(cv::countNonZero(prepare::snap_outline_to_photo(flat.photo, cut) != cut) == 0);
}

TEST_CASE("mask outline: the same outline whatever lies beyond the filter's reach, at any place in the photo") {
  // Only the animal's box and two windows round it are filtered (a photo of many megapixels): the
  // scene set into a larger photo, anything else beyond, gives the same mask at the same place.
  const Scene s = make_scene(Coat::tan);
  const cv::Mat cut = cut_like_grabcut(s.truth);
  prepare::OutlineOptions o;
  o.radius = 5, o.band = 3;  // the 200 px scene's; by default they follow the photo's size
  const cv::Mat alone = prepare::snap_outline_to_photo(s.photo, cut, o);
  cv::Mat photo(360, 400, CV_8UC3), mask = cv::Mat::zeros(360, 400, CV_8U);
  cv::randu(photo, cv::Scalar::all(0), cv::Scalar::all(255));
  const cv::Rect at(150, 110, kSize, kSize);
  s.photo.copyTo(photo(at));
  cut.copyTo(mask(at));
  const cv::Mat placed = prepare::snap_outline_to_photo(photo, mask, o);
  CHECK(cv::countNonZero(placed(at) != alone) == 0);
  CHECK(cv::countNonZero(placed) == cv::countNonZero(alone));  // nothing outside the scene's square
  CHECK(cv::countNonZero(alone != cut) > 0);  // the outline did move
}
