// prepare's check of an automatic mask against its photo's own keypoints (keypoint_cover.hpp): a
// mask where the photo shows the animal holds its animal keypoints and no background ones; one
// drawn where a wrong pose puts the animal refutes the pose. Made-up masks and keypoints, no COLMAP.
#include <doctest/doctest.h>

#include "engine/prepare/keypoint_cover.hpp"

using namespace nf;

namespace {

constexpr std::uint32_t kWidth = 200, kHeight = 150;

// An ellipse of animal, moved by `shift` pixels to the right, grown by `grow`.
std::vector<std::uint8_t> ellipse_mask(int shift, double grow = 0) {
  std::vector<std::uint8_t> m(std::size_t(kWidth) * kHeight, 0);
  for (std::uint32_t y = 0; y < kHeight; ++y)
    for (std::uint32_t x = 0; x < kWidth; ++x) {
      const double u = (double(x) + 0.5 - 80 - shift) / (50 + grow), v = (double(y) + 0.5 - 75) / (30 + grow);
      m[std::size_t(y) * kWidth + x] = u * u + v * v <= 1;
    }
  return m;
}

// Animal keypoints inside the true ellipse, background ones on a grid outside it.
struct Keypoints {
  std::vector<io::Camera> cameras;
  prepare::SparsePoints points;
  std::vector<char> animal, background;
  Keypoints(std::size_t animal_count, bool with_background) {
    io::Camera c;
    c.name = "000", c.width = kWidth, c.height = kHeight, c.image = "000.png";
    cameras.push_back(c);
    const std::vector<std::uint8_t> truth = ellipse_mask(0);
    auto& seen = points.observed["000.png"];
    for (std::size_t k = 0; k < animal_count; ++k) {
      const double a = 2 * M_PI * double(k) / double(animal_count);
      seen.push_back({{80 + 35 * std::cos(a), 75 + 20 * std::sin(a)}, points.positions.size()});
      points.positions.emplace_back(), animal.push_back(1), background.push_back(0);
    }
    if (with_background)
      for (std::uint32_t y = 5; y < kHeight; y += 10)
        for (std::uint32_t x = 5; x < kWidth; x += 10)
          if (!truth[std::size_t(y) * kWidth + x]) {
            seen.push_back({{double(x), double(y)}, points.positions.size()});
            points.positions.emplace_back(), animal.push_back(0), background.push_back(1);
          }
  }
  prepare::KeypointCover cover(const std::vector<std::uint8_t>& mask) const { return prepare::animal_keypoint_cover(cameras, points, animal, background, {mask}).front(); }
};

}  // namespace

TEST_CASE("keypoint cover: the true mask, and a fatter one, hold the animal's keypoints and no background ones") {
  const Keypoints k(20, true);
  for (const double grow : {0.0, 4.0}) {
    const prepare::KeypointCover c = k.cover(ellipse_mask(0, grow));
    CHECK(c.seen == 20);
    CHECK(c.inside == 20);
    // The fat one's rim takes a few of the background's keypoints next to the outline, far from a patch's worth.
    CHECK(double(c.background_inside) <= (grow > 0 ? 0.25 * c.background_expected : 0.0));
    CHECK(c.background_expected > 15);
    CHECK_FALSE(c.refutes());
  }
}

TEST_CASE("keypoint cover: a mask drawn where a wrong pose puts the animal refutes the pose, and says why") {
  const Keypoints k(20, true);
  const prepare::KeypointCover c = k.cover(ellipse_mask(90));
  MESSAGE("moved 90 px: ", c.inside, " of ", c.seen, " animal keypoints, ", c.background_inside, " background ones against ", c.background_expected);
  CHECK(2 * c.inside < c.seen);
  CHECK(c.background_inside >= 5);
  CHECK(c.refutes());
  CHECK(c.reason().find("of the 20 keypoints its photo has on the animal") != std::string::npos);
  // Either sign of evidence alone refutes it: the animal's keypoints, or the background's.
  CHECK(Keypoints(20, false).cover(ellipse_mask(90)).refutes());
  CHECK(Keypoints(0, true).cover(ellipse_mask(90)).refutes());
  // An empty mask holds none of the animal's keypoints.
  CHECK(k.cover(std::vector<std::uint8_t>(std::size_t(kWidth) * kHeight, 0)).refutes());
}

TEST_CASE("keypoint cover: too few keypoints (under 8 on the animal, no background), or a mask of another size, conclude nothing") {
  CHECK_FALSE(Keypoints(7, false).cover(ellipse_mask(90)).refutes());
  CHECK(Keypoints(8, false).cover(ellipse_mask(90)).refutes());
  const prepare::KeypointCover wrong_size = Keypoints(20, true).cover(std::vector<std::uint8_t>(10, 1));
  CHECK(wrong_size.seen == 0);
  CHECK_FALSE(wrong_size.refutes());
}
