// prepare's floor evidence (floor_consistency.hpp) and the poses it refutes: photos of a textured
// floor round a ball, rendered here through a ring of cameras. Through the right poses most judged
// floor pixels agree with the other photos; a photo given a pose turned 40 degrees round the ring
// (as COLMAP may place one), or 5, matches almost nowhere and is refuted, with a reason; 1 degree
// is not, nor a pose panned 0.75 degrees (a degree's slack brings it back), nor a photo 1.5 times
// brighter (patch correlation); an untextured floor judges nothing and refutes nothing.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/prepare/floor_consistency.hpp"
#include "engine/synth/camera_rig.hpp"

using namespace nf;

namespace {

constexpr std::uint32_t kSize = 160;
const glm::dvec3 kBall(0.0, 0.2, 0.0);
constexpr double kBallRadius = 0.2;
constexpr double kFramed = 0.6;  // the radius the cameras frame: the floor shows round the ball, as round an animal

double hash01(std::int64_t i, std::int64_t j, std::uint32_t seed) {
  std::uint64_t x = std::uint64_t(i) * 0x9E3779B97F4A7C15ULL ^ std::uint64_t(j) * 0xC2B2AE3D27D4EB4FULL ^ seed;
  x ^= x >> 31, x *= 0xBF58476D1CE4E5B9ULL, x ^= x >> 29;
  return double(x >> 11) / double(1ULL << 53);
}

// Value noise: random grey levels on a grid of `cell`, bilinear between.
double noise(double u, double v, double cell, std::uint32_t seed) {
  const double x = u / cell, y = v / cell;
  const double fx = x - std::floor(x), fy = y - std::floor(y);
  const auto i = std::int64_t(std::floor(x)), j = std::int64_t(std::floor(y));
  return (1 - fy) * ((1 - fx) * hash01(i, j, seed) + fx * hash01(i + 1, j, seed)) + fy * ((1 - fx) * hash01(i, j + 1, seed) + fx * hash01(i + 1, j + 1, seed));
}

// The grey level camera `c` sees along unit ray `d`: the ball (its own pattern) in front of the
// floor y = 0, a floor of one grey when `textured` is false, a flat sky above the horizon.
double radiance(const io::Camera& c, const glm::dvec3& d, bool textured) {
  const glm::dvec3 o = c.centre(), oc = o - kBall;
  const double b = glm::dot(oc, d), disc = b * b - (glm::dot(oc, oc) - kBallRadius * kBallRadius);
  if (disc > 0) {
    const glm::dvec3 p = o + (-b - std::sqrt(disc)) * d - kBall;
    return 40 + 150 * noise(std::atan2(p.z, p.x), p.y, 0.08, 7);
  }
  if (d.y >= 0) return 200;
  const glm::dvec3 p = o + (-o.y / d.y) * d;
  return textured ? 30 + 120 * noise(p.x, p.z, 0.04, 1) + 80 * noise(p.x, p.z, 0.02, 2) : 120;
}

// The photo camera `c` takes (grey, 0-255), 4 x 4 samples a pixel (as a lens and sensor blur the
// floor's detail where it recedes, instead of aliasing it), times `gain`, clipped.
cv::Mat photograph(const io::Camera& c, bool textured, double gain = 1.0) {
  cv::Mat grey(int(c.height), int(c.width), CV_32F);
  for (std::uint32_t y = 0; y < c.height; ++y)
    for (std::uint32_t x = 0; x < c.width; ++x) {
      double sum = 0;
      for (int sy = 0; sy < 4; ++sy)
        for (int sx = 0; sx < 4; ++sx)
          sum += radiance(c, glm::normalize(c.unproject({x + (sx + 0.5) / 4, y + (sy + 0.5) / 4}, 1.0) - c.centre()), textured);
      grey.at<float>(int(y), int(x)) = float(std::min(255.0, gain * sum / 16));
    }
  return grey;
}

struct Ring {
  std::vector<io::Camera> cameras;
  std::vector<cv::Mat> grey;
  prepare::FloorPlane floor;  // y = 0, up
  Ring(bool textured) {
    synth::RigOptions r;
    r.views = 16, r.width = r.height = kSize;
    cameras = synth::camera_rings(glm::vec3(kBall), float(kFramed), glm::vec3(0, 1, 0), r);
    for (const io::Camera& c : cameras) grey.push_back(photograph(c, textured));
  }
  prepare::FloorAgreement view_agreement(std::size_t i, const std::vector<char>* left_out = nullptr, double slack_deg = 0) const {
    const auto agreement_at = [&](glm::dvec2 shift, int stride) {
      return prepare::agreement_of(
          prepare::floor_evidence(cameras, grey, i, floor, glm::dvec3(0.0), 2 * kFramed, cv::Rect(0, 0, int(kSize), int(kSize)), stride, left_out, shift), stride);
    };
    if (slack_deg <= 0) return agreement_at(glm::dvec2(0.0), 1);
    return prepare::best_shifted_agreement(agreement_at, cameras[i].fx * std::tan(glm::radians(slack_deg)), 1);
  }
  std::vector<prepare::FloorAgreement> agreement(const std::vector<char>* left_out = nullptr) const {
    std::vector<prepare::FloorAgreement> a(cameras.size());
    for (std::size_t i = 0; i < cameras.size(); ++i)
      if (!(left_out && (*left_out)[i])) a[i] = view_agreement(i, left_out);
    return a;
  }
  // prepare's refutation: candidates judged again with a degree's slack, one at a time.
  std::vector<prepare::FloorRefutation> refute() const {
    std::vector<char> left_out(cameras.size(), 0);
    std::vector<prepare::FloorAgreement> a;
    return prepare::refute_poses_by_floor(a, left_out, [&] { return agreement(&left_out); },
                                          [&](std::size_t i) { return view_agreement(i, &left_out, prepare::kFloorSlackDeg); });
  }
};

}  // namespace

TEST_CASE("floor agreement: through the right poses the floor matches; a pose turned 40 degrees round the ring is refuted") {
  Ring ring(true);
  const std::vector<prepare::FloorAgreement> right = ring.agreement();
  double least = 1;
  for (const prepare::FloorAgreement& a : right) {
    least = std::min(least, a.share());
    CHECK(a.judged() > kSize * kSize / 20);
  }
  const double median = prepare::median_floor_agreement(right);
  MESSAGE("right poses: median agreeing share ", median, ", least ", least);
  CHECK(median > 0.8);
  CHECK(prepare::floor_refuted_views(right).empty());
  CHECK(ring.refute().empty());

  // View 3's photo kept, its pose turned about the vertical through the ball (still aimed at it).
  const auto turned_by = [&](double degrees) {
    const glm::dmat4 turn = glm::translate(glm::dmat4(1.0), kBall) * glm::rotate(glm::dmat4(1.0), glm::radians(degrees), glm::dvec3(0, 1, 0)) *
                            glm::translate(glm::dmat4(1.0), -kBall);
    Ring turned = ring;
    turned.cameras[3].camera_to_world = turn * ring.cameras[3].camera_to_world;
    return turned.agreement();
  };
  const std::vector<prepare::FloorAgreement> wrong = turned_by(40);
  MESSAGE("view 3 turned 40 degrees: ", wrong[3].share(), " of ", wrong[3].judged(), " judged pixels agree");
  CHECK(wrong[3].share() < 0.2);
  REQUIRE(prepare::floor_refuted_views(wrong) == std::vector<std::size_t>{3});
  {
    Ring turned = ring;
    turned.cameras[3].camera_to_world = glm::translate(glm::dmat4(1.0), kBall) * glm::rotate(glm::dmat4(1.0), glm::radians(40.0), glm::dvec3(0, 1, 0)) *
                                        glm::translate(glm::dmat4(1.0), -kBall) * ring.cameras[3].camera_to_world;
    const std::vector<prepare::FloorRefutation> refuted = turned.refute();
    REQUIRE(refuted.size() == 1);
    CHECK(refuted[0].view == 3);
    MESSAGE("refuted: ", refuted[0].reason);
    CHECK(refuted[0].reason.find("matches the other photos' floor at") != std::string::npos);
    CHECK(refuted[0].reason.find("with a degree's slack") != std::string::npos);
    CHECK(refuted[0].reason.find("its pose is wrong") != std::string::npos);
    // The slack is one shift for the whole photo, so no shift makes a wrong pose's floor agree:
    // the best shift of each patch on its own let such a pose agree at 28-30 % on synth floors.
    CHECK(turned.view_agreement(3, nullptr, prepare::kFloorSlackDeg).share() < 0.05);  // measured 0.009
  }
  // How small a turn round the ring it sees.
  const std::vector<prepare::FloorAgreement> by5 = turned_by(5), by2 = turned_by(2), by1 = turned_by(1);
  MESSAGE("turned 5, 2, 1 degrees: ", by5[3].share(), ", ", by2[3].share(), ", ", by1[3].share(), " agree");
  CHECK(prepare::floor_refuted_views(by5) == std::vector<std::size_t>{3});
  CHECK(prepare::floor_refuted_views(by1).empty());

  // A pose panned 0.75 degrees on the spot (as COLMAP's right poses may be at small sizes: a
  // 3-pixel shift) can look refuted to the strict check on a fine floor, but a degree's slack
  // brings it back, and it is kept.
  Ring panned = ring;
  panned.cameras[3].camera_to_world = ring.cameras[3].camera_to_world * glm::rotate(glm::dmat4(1.0), glm::radians(0.75), glm::dvec3(0, 1, 0));
  const std::vector<prepare::FloorAgreement> pan = panned.agreement();
  const prepare::FloorAgreement pan_slack = panned.view_agreement(3, nullptr, prepare::kFloorSlackDeg);
  MESSAGE("panned 0.75 degrees: ", pan[3].share(), " agree, ", pan_slack.share(), " with a degree's slack");
  CHECK(pan[3].share() < median / 3);  // a candidate to the strict check (measured 0.25)
  CHECK(pan_slack.share() > 0.8 * median);  // measured 0.94
  CHECK(panned.refute().empty());

  // A photo 1.5 times brighter (its sky and highlights clipped): the patches still correlate.
  Ring brighter = ring;
  brighter.grey[5] = photograph(ring.cameras[5], true, 1.5);
  const std::vector<prepare::FloorAgreement> bright = brighter.agreement();
  MESSAGE("view 5 1.5 times brighter: ", bright[5].share(), " agree (", right[5].share(), " before)");
  CHECK(bright[5].share() > 0.8 * right[5].share());
  CHECK(prepare::floor_refuted_views(bright).empty());
}

TEST_CASE("floor agreement: an untextured floor judges nothing, so no pose is refuted by it") {
  Ring ring(false);
  const std::vector<prepare::FloorAgreement> flat = ring.agreement();
  std::size_t judged = 0;
  for (const prepare::FloorAgreement& a : flat) judged += a.judged();
  MESSAGE("judged pixels on an untextured floor, all views: ", judged);
  CHECK(prepare::median_floor_agreement(flat) < 0.5);  // the ball's own pixels at most
  CHECK(prepare::floor_refuted_views(flat).empty());
  // Counts that say too little: under 1 % of the photo judged, or a median under a half.
  const std::size_t pixels = 10000;
  std::vector<prepare::FloorAgreement> few(8, prepare::FloorAgreement{900, 100, pixels});
  few[2] = {0, 99, pixels};  // 0.99 % judged
  CHECK(prepare::floor_refuted_views(few).empty());
  few[2] = {0, 100, pixels};  // 1 %: judged, and refuted
  CHECK(prepare::floor_refuted_views(few) == std::vector<std::size_t>{2});
  std::vector<prepare::FloorAgreement> unlike(8, prepare::FloorAgreement{400, 600, pixels});
  unlike[4] = {0, 1000, pixels};
  CHECK(prepare::floor_refuted_views(unlike).empty());
}
