// Gabor orientation maps (engine/orient): GPU against the CPU reference, known angles on synthetic
// gratings and lines, the angle convention, masks, odd sizes, bands, files and the angle metric.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>

#include "engine/core/error.hpp"
#include "engine/orient/angle_error.hpp"
#include "engine/orient/gabor_ref.hpp"
#include "engine/orient/orientation_io.hpp"
#include "engine/orient/orientation_map.hpp"
#include "tests/support/gpu_test.hpp"

namespace nf::orient {
namespace {

constexpr double kDeg = kPi / 180.0;

io::Image grey_image(std::uint32_t w, std::uint32_t h, const std::function<double(double, double)>& value) {
  io::Image image{w, h, 1, std::vector<float>(std::size_t(w) * h)};
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x) image.pixels[std::size_t(y) * w + x] = float(value(x, y));
  return image;
}

// Coordinate across strands of orientation theta (degrees): p . n, n = (sin theta, cos theta).
double across(double x, double y, double theta_deg) {
  return x * std::sin(theta_deg * kDeg) + y * std::cos(theta_deg * kDeg);
}

io::Image grating(double theta_deg, double period, std::uint32_t size = 64) {
  return grey_image(size, size, [=](double x, double y) {
    return 0.5 + 0.5 * std::cos(2 * kPi * across(x, y, theta_deg) / period);
  });
}

// Thin (sigma 0.6 px) dark lines, `spacing` px apart, on a bright background.
io::Image dark_lines(double theta_deg, double spacing, std::uint32_t size = 64) {
  return grey_image(size, size, [=](double x, double y) {
    const double a = across(x, y, theta_deg) - spacing * std::floor(across(x, y, theta_deg) / spacing);
    const double d = std::min(a, spacing - a);
    return 0.9 - 0.7 * std::exp(-d * d / (2 * 0.6 * 0.6));
  });
}

io::Image random_rgb(std::uint32_t w, std::uint32_t h, std::uint32_t seed) {
  return {w, h, 3, test::random_f32(std::size_t(w) * h * 3, seed, 0.f, 1.f)};
}

// Pixels at least `margin` px from every border.
std::vector<std::size_t> interior(std::uint32_t w, std::uint32_t h, std::uint32_t margin) {
  std::vector<std::size_t> out;
  for (std::uint32_t y = margin; y + margin < h; ++y)
    for (std::uint32_t x = margin; x + margin < w; ++x) out.push_back(std::size_t(y) * w + x);
  return out;
}

float max_of(const std::vector<float>& v) { return v.empty() ? 0.f : *std::max_element(v.begin(), v.end()); }

// Confidence of responses f (one per orientation) around bin m, as gabor_ref.hpp defines it.
double confidence_at(const GaborBank& bank, const double* f, std::uint32_t m) {
  double spread = 0;
  for (std::uint32_t i = 0; i < bank.orientations; ++i) {
    const double d = orientation_distance(bank.theta(i), bank.theta(m));
    spread += d * d * (f[i] - f[m]) * (f[i] - f[m]);
  }
  return std::sqrt(spread / bank.distance2_sum);
}

// GPU against the CPU reference. Orientation: the same bin, or one whose reference response ties
// the maximum to 1e-5 (float rounding may pick either). Confidence: to 1e-4 of the largest (or of
// 1e-3, a faint texture's confidence, for images with none), measured around the GPU's bin.
void check_against_reference(const io::Image& image, const std::vector<std::uint8_t>* mask,
                             const GaborParams& params = {}) {
  const OrientationMap gpu = gabor_orientation(test::context(), image, mask, params);
  const OrientationRef ref =
      gabor_orientation_ref(luminance(image), image.width, image.height, mask, params, /*keep_responses=*/true);
  const GaborBank bank = make_gabor_bank(params);
  const std::size_t n = ref.confidence.size();
  REQUIRE(gpu.confidence.pixels.size() == n);
  const double scale = std::max(max_of(ref.confidence), 1e-3f);
  double conf_error = 0;
  for (std::size_t i = 0; i < n; ++i) {
    CAPTURE(i);
    REQUIRE(std::isfinite(gpu.confidence.pixels[i]));
    REQUIRE(std::isfinite(gpu.orientation.pixels[i]));
    if (mask && !(*mask)[i]) continue;
    const auto m_gpu = std::uint32_t(std::lround(gpu.orientation.pixels[i] / (kPi / params.orientations)));
    const auto m_ref = std::uint32_t(std::lround(ref.orientation[i] / (kPi / params.orientations)));
    REQUIRE(m_gpu < params.orientations);
    const double* f = &ref.responses[i * params.orientations];
    if (m_gpu != m_ref) {
      REQUIRE(f[m_gpu] >= f[m_ref] * (1 - 1e-5));
    }
    conf_error = std::max(conf_error, std::fabs(gpu.confidence.pixels[i] - confidence_at(bank, f, m_gpu)));
  }
  CHECK(conf_error / scale < 1e-4);
}

// Largest undirected angle error (degrees) over `pixels`.
double max_angle_error_deg(const OrientationMap& map, const std::vector<std::size_t>& pixels, double theta_deg) {
  double worst = 0;
  for (const std::size_t i : pixels)
    worst = std::max(worst, orientation_distance(map.orientation.pixels[i], theta_deg * kDeg) / kDeg);
  return worst;
}

}  // namespace

// The kernel's layouts for GPUs (1 pixel per invocation) and CPU devices (4).
GaborParams with_pixels(std::uint32_t pixels) {
  GaborParams params;
  params.pixels_per_invocation = pixels;
  return params;
}
constexpr std::uint32_t kLayouts[] = {1, 4};

TEST_CASE("GPU orientation and confidence match the CPU reference on a random image") {
  for (const std::uint32_t pixels : kLayouts) {
    CAPTURE(pixels);
    check_against_reference(random_rgb(37, 29, 1), nullptr, with_pixels(pixels));
  }
  // A bank too large for one uniform buffer (360 x 21 vec4) takes its weights from a storage
  // buffer; a tiny one, and other filter shapes, go through the same code.
  // (One pixel per invocation: the other layouts are covered above and cost seconds to compile.)
  GaborParams fine = with_pixels(1);
  fine.orientations = 360;
  check_against_reference(random_rgb(21, 18, 2), nullptr, fine);
  GaborParams coarse = with_pixels(1);
  coarse.orientations = 6;
  coarse.sigma_x = 1.2f;
  coarse.sigma_y = 3.1f;
  coarse.frequency = 0.3f;
  coarse.dog_high_sigma = 0;
  check_against_reference(random_rgb(21, 18, 3), nullptr, coarse);
}

TEST_CASE("1x1, thin and non-multiple-of-16 images match the reference") {
  for (const auto& [w, h] : {std::pair{1u, 1u}, {1u, 9u}, {13u, 1u}, {17u, 33u}, {16u, 16u}}) {
    CAPTURE(w);
    CAPTURE(h);
    for (const std::uint32_t pixels : kLayouts) {
      CAPTURE(pixels);
      check_against_reference(random_rgb(w, h, w * 100 + h), nullptr, with_pixels(pixels));
    }
  }
}

TEST_CASE("a mask confines the work: outside is 0, inside is unchanged") {
  const io::Image image = random_rgb(40, 23, 7);
  std::vector<std::uint8_t> mask(40 * 23);
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = ((i * 7919) % 11) < 6 ? 1 : 0;
  for (const std::uint32_t pixels : kLayouts) check_against_reference(image, &mask, with_pixels(pixels));
  const OrientationMap full = gabor_orientation(test::context(), image, nullptr);
  const OrientationMap masked = gabor_orientation(test::context(), image, &mask);
  for (std::size_t i = 0; i < mask.size(); ++i) {
    CAPTURE(i);
    if (mask[i]) {
      REQUIRE(masked.orientation.pixels[i] == full.orientation.pixels[i]);
      REQUIRE(masked.confidence.pixels[i] == full.confidence.pixels[i]);
    } else {
      REQUIRE(masked.orientation.pixels[i] == 0.f);
      REQUIRE(masked.confidence.pixels[i] == 0.f);
    }
  }
  const std::vector<std::uint8_t> empty(mask.size(), 0);
  CHECK(max_of(gabor_orientation(test::context(), image, &empty).confidence.pixels) == 0.f);
}

TEST_CASE("bands of rows give the same map as the whole image") {
  const io::Image image = random_rgb(40, 37, 3);
  std::vector<std::uint8_t> mask(40 * 37);
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = (i / 40 + i % 40) % 3 != 0;
  GaborParams banded;
  banded.band_rows = 5;
  const std::vector<std::uint8_t>* masks[] = {nullptr, &mask};
  for (const std::vector<std::uint8_t>* m : masks) {
    const OrientationMap whole = gabor_orientation(test::context(), image, m);
    const OrientationMap bands = gabor_orientation(test::context(), image, m, banded);
    CHECK(bands.orientation.pixels == whole.orientation.pixels);
    CHECK(bands.confidence.pixels == whole.confidence.pixels);
  }
}

// Interior pixels whose confidence is at least 5 % of the interior's largest. Where a grating's
// local phase crosses zero every filter's response vanishes together (the spatial phase factors
// out of all of them), so the argmax there is decided by rounding and by the faint border effects
// of the DoG; the confidence says so, and consumers weigh by it.
std::vector<std::size_t> confident_interior(const OrientationMap& map, std::uint32_t margin) {
  const std::vector<std::size_t> inner = interior(map.confidence.width, map.confidence.height, margin);
  float top = 0;
  for (const std::size_t i : inner) top = std::max(top, map.confidence.pixels[i]);
  std::vector<std::size_t> out;
  for (const std::size_t i : inner)
    if (map.confidence.pixels[i] >= 0.05f * top) out.push_back(i);
  CHECK(out.size() >= inner.size() * 9 / 10);  // the test is not vacuous
  return out;
}

constexpr double kOneDegree = 1.0 + 1e-4;  // a one-bin error is "within 1 degree"

TEST_CASE("sinusoidal gratings (period 4.3 px) give their angle in the interior") {
  for (const double theta : {0.0, 17.0, 45.0, 90.0, 133.0}) {
    CAPTURE(theta);
    const OrientationMap map = gabor_orientation(test::context(), grating(theta, 4.3), nullptr);
    CHECK(max_angle_error_deg(map, confident_interior(map, 12), theta) <= kOneDegree);
  }
}

TEST_CASE("thin dark lines give their angle in the interior") {
  for (const double theta : {0.0, 17.0, 45.0, 90.0, 133.0}) {
    CAPTURE(theta);
    // Lines as dense as the filters' period: every confident interior pixel.
    const OrientationMap dense = gabor_orientation(test::context(), dark_lines(theta, 4.3), nullptr);
    CHECK(max_angle_error_deg(dense, confident_interior(dense, 12), theta) <= kOneDegree);
    // Lines 7 px apart: the pixels on a line. (Between sparse lines the even filters' response
    // depends on the distance to the line, as in the reference, and the argmax may drift there.)
    const OrientationMap sparse = gabor_orientation(test::context(), dark_lines(theta, 7.0), nullptr);
    std::vector<std::size_t> on_line;
    for (const std::size_t i : interior(64, 64, 12)) {
      const double a = across(double(i % 64), double(i / 64), theta);
      if (std::fabs(a - 7.0 * std::round(a / 7.0)) <= 0.5) on_line.push_back(i);
    }
    REQUIRE(on_line.size() > 100);
    CHECK(max_angle_error_deg(sparse, on_line, theta) <= kOneDegree);
  }
}

TEST_CASE("angle convention: a line from (0,0) towards (+x,-y) on screen is 45 degrees") {
  CHECK(orientation_of_direction(1, -1) == doctest::Approx(45 * kDeg));
  CHECK(orientation_of_direction(-1, 1) == doctest::Approx(45 * kDeg));  // undirected
  CHECK(orientation_of_direction(0, 1) == doctest::Approx(90 * kDeg));
  CHECK(orientation_of_direction(1, 1) == doctest::Approx(135 * kDeg));
  // One dark line through the centre of a 41x41 image, running up and to the right on screen.
  const io::Image image = grey_image(41, 41, [](double x, double y) {
    const double d = ((x - 20) + (y - 20)) / std::sqrt(2.0);  // distance to the line x - 20 = -(y - 20)
    return 0.9 - 0.7 * std::exp(-d * d / (2 * 0.6 * 0.6));
  });
  const OrientationMap map = gabor_orientation(test::context(), image, nullptr);
  CHECK(map.orientation.pixels[20 * 41 + 20] == doctest::Approx(45 * kDeg).epsilon(1e-6));
}

TEST_CASE("a constant image has no confidence") {
  const io::Image flat = grey_image(48, 40, [](double, double) { return 0.6; });
  const float strong = max_of(gabor_orientation(test::context(), grating(30, 4.3, 48), nullptr).confidence.pixels);
  CHECK(strong > 0.01f);
  CHECK(max_of(gabor_orientation(test::context(), flat, nullptr).confidence.pixels) <= 1e-6f * strong);
}

TEST_CASE("bad inputs are rejected with errors that name them") {
  const io::Image image = random_rgb(8, 8, 5);
  const std::vector<std::uint8_t> short_mask(10, 1);
  CHECK_THROWS_AS(gabor_orientation(test::context(), image, &short_mask), InputError);
  CHECK_THROWS_AS(gabor_orientation(test::context(), io::Image{}, nullptr), InputError);
  io::Image nan_image = image;
  nan_image.pixels[5] = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_WITH_AS(gabor_orientation(test::context(), nan_image, nullptr), doctest::Contains("image"), InputError);
  GaborParams bad;
  bad.orientations = 1;
  CHECK_THROWS_WITH_AS(gabor_orientation(test::context(), image, nullptr, bad), doctest::Contains("orientations"),
                       InputError);
  bad = {};
  bad.pixels_per_invocation = 3;
  CHECK_THROWS_WITH_AS(make_gabor_bank(bad), doctest::Contains("pixels_per_invocation"), InputError);
  bad = {};
  bad.sigma_y = -1;
  CHECK_THROWS_WITH_AS(make_gabor_bank(bad), doctest::Contains("sigma_y"), InputError);
}

TEST_CASE("orientation maps round-trip through EXR and visualise as hue and value") {
  const OrientationMap map = gabor_orientation(test::context(), grating(60, 4.3, 32), nullptr);
  const auto dir = std::filesystem::temp_directory_path() / "nf_test_orient";
  std::filesystem::create_directories(dir);
  write_orientation_exr(dir / "map.exr", map);
  const OrientationMap back = read_orientation_exr(dir / "map.exr");
  CHECK(back.orientation.pixels == map.orientation.pixels);
  CHECK(back.confidence.pixels == map.confidence.pixels);
  write_orientation_png(dir / "map.png", map);
  CHECK(std::filesystem::file_size(dir / "map.png") > 0);
  std::filesystem::remove_all(dir);

  // theta 0 and theta 90 degrees: red and cyan (hue of the doubled angle); no confidence: black.
  OrientationMap tiny;
  tiny.orientation = {3, 1, 1, {0.f, float(kPi / 2), 1.f}};
  tiny.confidence = {3, 1, 1, {2.f, 2.f, 0.f}};
  const io::Image vis = orientation_visualisation(tiny);
  CHECK(vis.at(0, 0, 0) == doctest::Approx(1.0));
  CHECK(vis.at(0, 0, 1) == doctest::Approx(0.0));
  CHECK(vis.at(1, 0, 0) == doctest::Approx(0.0));
  CHECK(vis.at(1, 0, 1) == doctest::Approx(1.0));
  CHECK(vis.at(1, 0, 2) == doctest::Approx(1.0));
  CHECK(vis.at(2, 0, 0) + vis.at(2, 0, 1) + vis.at(2, 0, 2) == 0.f);
}

TEST_CASE("median undirected angle difference on hand-made maps") {
  auto img = [](std::vector<float> v) { return io::Image{std::uint32_t(v.size()), 1, 1, std::move(v)}; };
  const float d = float(kDeg);
  // Differences: 10, 1 (179 vs 0 wraps), 90, 30 (invalid), 50 (no confidence).
  const io::Image orientation = img({10 * d, 179 * d, 90 * d, 30 * d, 50 * d});
  const io::Image reference = img({0, 0, 0, 0, 0});
  const io::Image confidence = img({1, 1, 1, 1, 0});
  const std::vector<std::uint8_t> valid = {1, 1, 1, 0, 1};
  CHECK(median_angle_difference_deg(orientation, confidence, reference, valid) == doctest::Approx(10).epsilon(1e-5));
  // An even count takes the mean of the middle two: {1, 10, 30, 90} -> 20.
  const std::vector<std::uint8_t> all = {1, 1, 1, 1, 1};
  CHECK(median_angle_difference_deg(orientation, confidence, reference, all) == doctest::Approx(20).epsilon(1e-5));
  // Directions given the other way round (reference 180 + x) are the same orientations.
  const io::Image flipped = img({float(kPi) + 10 * d, float(kPi) + 179 * d, float(kPi) + 90 * d, 0, 0});
  CHECK(median_angle_difference_deg(orientation, confidence, flipped, valid) == doctest::Approx(0).epsilon(1e-4));
  CHECK(std::isnan(median_angle_difference_deg(orientation, confidence, reference, std::vector<std::uint8_t>(5, 0))));
  CHECK_THROWS_AS(median_angle_difference_deg(orientation, confidence, img({0, 0}), valid), InputError);
}

}  // namespace nf::orient
