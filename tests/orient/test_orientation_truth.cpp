// An orientation map judged against the true one (orientation_truth.hpp): errors, the reliable
// share and the bins by reliability on maps whose every error is known.
#include <doctest/doctest.h>

#include <cmath>

#include "engine/core/error.hpp"
#include "engine/orient/orientation_truth.hpp"

using namespace nf;

namespace {

io::Image plane(std::uint32_t w, std::uint32_t h, float value) { return {w, h, 1, std::vector<float>(std::size_t(w) * h, value)}; }

}  // namespace

TEST_CASE("orientation against the truth: medians, the reliable share and the bins by reliability") {
  const std::uint32_t W = 40, H = 40;
  const float deg = 3.14159265f / 180.f;
  orient::OrientationMap truth{plane(W, H, 170 * deg), plane(W, H, 1.f)};
  orient::OrientationMap map{plane(W, H, 0.f), plane(W, H, 1.f)};
  std::vector<float> reliability(std::size_t(W) * H);
  std::vector<std::uint8_t> mask(std::size_t(W) * H, 1);
  // Left half: 5 degrees off across the wrap (175 against 170: 5), reliability 0.9; right half: 30 degrees off, reliability 0.1.
  for (std::uint32_t y = 0; y < H; ++y)
    for (std::uint32_t x = 0; x < W; ++x) {
      const std::size_t i = std::size_t(y) * W + x;
      map.orientation.pixels[i] = x < W / 2 ? 175 * deg : 20 * deg;
      reliability[i] = x < W / 2 ? 0.9f : 0.1f;
    }
  truth.confidence.pixels[0] = 0.5f;  // a pixel the truth does not agree on is not scored (and lies in the outline anyway)
  const orient::TruthAgreement a = orient::agreement_with_truth(map, reliability, truth, mask, {.outline = 2});
  CHECK(a.pixels == 36u * 36u);  // the 2-pixel outline is left out
  CHECK(a.reliable_share == doctest::Approx(18.0 / 36.0));
  CHECK(a.median_error_reliable_deg == doctest::Approx(5.0).epsilon(1e-3));
  CHECK(a.median_error_deg == doctest::Approx(17.5).epsilon(1e-3));  // the mean of the two middle values, 5 and 30
  CHECK(a.weighted_error_deg == doctest::Approx((0.9 * 5 + 0.1 * 30) / 1.0).epsilon(1e-3));
  CHECK(a.mean_reliability == doctest::Approx(0.5).epsilon(1e-5));
  CHECK(a.median_error_by_reliability[0] == doctest::Approx(30.0).epsilon(1e-3));
  CHECK(a.median_error_by_reliability[4] == doctest::Approx(5.0).epsilon(1e-3));
  CHECK(a.share_by_reliability[0] == doctest::Approx(0.5));
  CHECK(a.share_by_reliability[2] == 0.0);

  // Pixels outside the mask are not scored; with none left, nothing is.
  std::vector<std::uint8_t> none(mask.size(), 0);
  CHECK(orient::agreement_with_truth(map, reliability, truth, none).pixels == 0u);
  orient::OrientationMap small{plane(W / 2, H, 0.f), plane(W / 2, H, 1.f)};
  CHECK_THROWS_WITH_AS(orient::agreement_with_truth(map, reliability, small, mask), doctest::Contains("20x40"), InputError);
}
