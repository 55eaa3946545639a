// Multi-scale orientation (engine/orient/orientation_scales): the GPU maps against the CPU
// reference through the same scale selection, the scale that resolves each stripe width winning,
// the reliability's two ends, and the halving.
#include <doctest/doctest.h>

#include <cmath>
#include <algorithm>
#include <random>

#include "engine/core/error.hpp"
#include "engine/orient/gabor_ref.hpp"
#include "engine/orient/orientation_scales.hpp"
#include "tests/support/gpu_test.hpp"

namespace nf::orient {
namespace {

constexpr double kDeg = kPi / 180.0;

// Stripes under pixel noise: fine ones (the bank's period) on the left half, and on the right half
// stripes twice as wide in another direction, which the bank sees through the noise only once the
// image is halved.
io::Image two_widths(std::uint32_t size) {
  io::Image image{size, size, 1, std::vector<float>(std::size_t(size) * size)};
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> noise(-0.5f, 0.5f);
  for (std::uint32_t y = 0; y < size; ++y)
    for (std::uint32_t x = 0; x < size; ++x) {
      const bool left = x < size / 2;
      const double theta = (left ? 30.0 : 120.0) * kDeg, period = left ? 4.35 : 8.7;
      const double across = x * std::sin(theta) + y * std::cos(theta);
      image.pixels[std::size_t(y) * size + x] = float(0.5 + 0.5 * std::cos(2 * kPi * across / period)) + noise(rng);
    }
  return image;
}

OrientationMap cpu_map(const io::Image& image, const std::vector<std::uint8_t>& mask) {
  const OrientationRef r = gabor_orientation_ref(luminance(image), image.width, image.height, &mask, GaborParams{});
  return {{image.width, image.height, 1, r.orientation}, {image.width, image.height, 1, r.confidence}};
}

}  // namespace

TEST_CASE("orientation scales: the GPU maps match the CPU reference, and each stripe width is read at the scale that resolves it") {
  gpu::Context& ctx = test::context();
  const std::uint32_t size = 96;
  const io::Image image = two_widths(size);
  const std::vector<std::uint8_t> mask(std::size_t(size) * size, 1);
  const OrientationOf gpu_map = [&](const io::Image& i, const std::vector<std::uint8_t>& m) { return gabor_orientation(ctx, i, &m); };
  const ScaledOrientation g = scaled_orientation(image, mask, 2, 9, gpu_map);
  const ScaledOrientation c = scaled_orientation(image, mask, 2, 9, cpu_map);
  const ScaledOrientation one = scaled_orientation(image, mask, 1, 9, cpu_map);
  REQUIRE(g.angle.size() == mask.size());
  double worst_angle = 0, worst_reliability = 0;
  std::size_t same_scale = 0, n = 0;
  std::size_t left_fine = 0, left = 0, right_coarse = 0, right = 0, right_right = 0, one_right = 0;
  double right_gain = 0;
  for (std::uint32_t y = 16; y + 16 < size; ++y)
    for (std::uint32_t x = 12; x + 12 < size; ++x) {
      if (x > size / 2 - 14 && x < size / 2 + 14) continue;  // the seam, where the windows see both
      const std::size_t i = std::size_t(y) * size + x;
      ++n;
      if (g.scale[i] == c.scale[i]) {
        ++same_scale;
        worst_angle = std::max(worst_angle, orientation_distance(g.angle[i], c.angle[i]));
        worst_reliability = std::max(worst_reliability, double(std::abs(g.reliability[i] - c.reliability[i])));
      }
      const bool is_left = x < size / 2;
      (is_left ? left : right) += 1;
      const double want = (is_left ? 30.0 : 120.0) * kDeg;
      if (is_left && c.scale[i] == 0) ++left_fine;
      if (!is_left && c.scale[i] == 1) ++right_coarse, right_gain += c.reliability[i] - one.reliability[i];
      if (!is_left) right_right += orientation_distance(c.angle[i], want) < 5 * kDeg, one_right += orientation_distance(one.angle[i], want) < 5 * kDeg;
    }
  // The GPU and CPU filters differ in rounding only: the same scale wins almost everywhere, and
  // where it does the angles and reliabilities agree.
  CHECK(double(same_scale) / double(n) > 0.98);
  CHECK(worst_angle < 1.01 * kDeg);  // at most one of the 180 bins
  CHECK(worst_reliability < 2e-3);
  // The fine stripes are read at the photo's scale, the wide ones at the halved photo's, where
  // the reliability is higher than the photo's own map gives.
  CHECK(double(left_fine) / double(left) > 0.9);
  CHECK(double(right_coarse) / double(right) > 0.9);
  CHECK(right_gain / double(std::max<std::size_t>(1, right_coarse)) > 0.1);
  // and their angles are right more often than the photo's own map has them.
  CHECK(double(right_right) / double(right) > 0.85);
  INFO("right: ", right_right, " of ", right, " within 5 deg (one scale: ", one_right, ")");
  CHECK(right_right > one_right);
  // One scale is the photo's map: never a coarse scale.
  for (std::uint8_t s : one.scale) REQUIRE(s == 0);
}

TEST_CASE("orientation scales: reliability is 1 for one orientation everywhere and near 0 for random ones") {
  const std::uint32_t w = 64, h = 48;
  OrientationMap same{{w, h, 1, std::vector<float>(w * h, 0.7f)}, {w, h, 1, std::vector<float>(w * h, 2.f)}};
  for (float r : orientation_reliability(same, 9)) REQUIRE(r == doctest::Approx(1.0).epsilon(1e-6));
  OrientationMap noise = same;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> angle(0.f, float(kPi));
  for (float& a : noise.orientation.pixels) a = angle(rng);
  double mean = 0;
  for (float r : orientation_reliability(noise, 9)) mean += r / double(w * h);
  CHECK(mean < 0.05);
  // No confidence: no reliability (not a division by zero).
  OrientationMap blank = same;
  std::fill(blank.confidence.pixels.begin(), blank.confidence.pixels.end(), 0.f);
  for (float r : orientation_reliability(blank, 9)) REQUIRE(r == 0.f);
}

TEST_CASE("orientation scales: halving averages 2 x 2 boxes, keeps an odd edge, and a mask pixel survives when any of its four is set") {
  const io::Image image{3, 3, 1, {1, 2, 3, 4, 5, 6, 7, 8, 9}};
  const io::Image h = halve(image);
  REQUIRE(h.width == 2);
  REQUIRE(h.height == 2);
  CHECK(h.pixels[0] == doctest::Approx(3.0));   // (1 + 2 + 4 + 5) / 4
  CHECK(h.pixels[1] == doctest::Approx(4.5));   // (3 + 6) / 2
  CHECK(h.pixels[2] == doctest::Approx(7.5));   // (7 + 8) / 2
  CHECK(h.pixels[3] == doctest::Approx(9.0));
  const std::vector<std::uint8_t> m = halve_mask({0, 0, 0, 0, 1, 0, 0, 0, 0}, 3, 3);
  CHECK(m == std::vector<std::uint8_t>{1, 0, 0, 0});
  CHECK_THROWS_AS(scaled_orientation(image, {1, 1}, 1, 9, cpu_map), InputError);
  CHECK_THROWS_AS(scaled_orientation(image, std::vector<std::uint8_t>(9, 1), 0, 9, cpu_map), InputError);
}

}  // namespace nf::orient

namespace nf::orient {

TEST_CASE("orientation scales: three scales on odd sizes, the photo's own map reused, and no coarse scale at the outline") {
  // Stripes four times the filters' period inside a disc, flat grey outside: the halved-twice map
  // resolves the stripes; near the disc's edge every scale also sees the edge itself.
  const std::uint32_t w = 131, h = 127;
  io::Image image{w, h, 1, std::vector<float>(std::size_t(w) * h, 0.5f)};
  std::vector<std::uint8_t> mask(image.pixels.size(), 0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> noise(-0.3f, 0.3f);
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x) {
      if (std::hypot(x - 65.0, y - 63.0) > 55) continue;
      const std::size_t i = std::size_t(y) * w + x;
      mask[i] = 1;
      const double across = x * std::sin(60 * kDeg) + y * std::cos(60 * kDeg);
      image.pixels[i] = float(0.5 + 0.5 * std::cos(2 * kPi * across / 17.4)) + noise(rng);
    }
  const OrientationMap own = cpu_map(image, mask);
  const ScaledOrientation guarded = scaled_orientation(image, mask, 3, 9, cpu_map, 8);
  const ScaledOrientation reused = scaled_orientation(image, mask, 3, 9, cpu_map, 8, &own);
  CHECK(reused.angle == guarded.angle);  // the map passed in is the one it would have made
  CHECK(reused.scale == guarded.scale);
  const ScaledOrientation open = scaled_orientation(image, mask, 3, 9, cpu_map, 0);
  const std::vector<std::uint8_t> inside = eroded_mask(mask, w, h, 8), deep = eroded_mask(mask, w, h, 30);
  std::size_t coarse_near_edge_open = 0, coarse_interior = 0, interior = 0;
  for (std::size_t i = 0; i < mask.size(); ++i) {
    REQUIRE(guarded.scale[i] <= 2);
    if (!mask[i]) continue;
    if (!inside[i]) {
      REQUIRE(guarded.scale[i] == 0);  // within 8 px of the outline: the photo's own scale
      coarse_near_edge_open += open.scale[i] > 0;
    } else if (deep[i]) {
      ++interior, coarse_interior += guarded.scale[i] == 2;
    }
  }
  MESSAGE("near the outline without the guard, ", coarse_near_edge_open, " pixels took a coarse scale");
  CHECK(coarse_near_edge_open > 0);                           // what the guard prevents
  CHECK(double(coarse_interior) / double(interior) > 0.8);    // the wide stripes, read twice halved
}

}  // namespace nf::orient
