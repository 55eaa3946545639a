// Strand metrics on analytic fixtures: identical sets, shifted and reversed copies, straight
// strands, known lengths, and independence from the order of strands.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "engine/metrics/strand_metrics.hpp"

using namespace nf;
using namespace nf::metrics;

namespace {

// A 12 x 12 grid of straight strands, 10 cm apart, each `length` cm along +y (1 unit = 1 cm).
io::StrandSet grid(double length, double shift_x = 0, bool reversed = false, std::uint32_t points = 20) {
  std::vector<float> xyz;
  for (int gx = 0; gx < 12; ++gx)
    for (int gz = 0; gz < 12; ++gz)
      for (std::uint32_t p = 0; p < points; ++p) {
        const double t = double(reversed ? points - 1 - p : p) / (points - 1);
        xyz.insert(xyz.end(), {float(10.0 * gx + shift_x), float(length * t), float(10.0 * gz)});
      }
  return io::StrandSet::uniform(144, points, xyz);
}

double fscore(const std::vector<MatchScore>& scores, double distance, bool directed) {
  for (const auto& s : scores)
    if (s.threshold.distance_cm == distance && s.directed == directed) return s.fscore;
  FAIL("threshold missing");
  return -1;
}

}  // namespace

TEST_CASE("identical sets score 100 at every threshold, directed and not") {
  const auto s = sample_strands(grid(5), 100000, 100, 1);
  for (const auto& score : match_scores(s, s, default_thresholds(), 1.0)) {
    CHECK(score.precision == doctest::Approx(100));
    CHECK(score.recall == doctest::Approx(100));
    CHECK(score.fscore == doctest::Approx(100));
  }
}

TEST_CASE("a copy shifted by 1.5 cm scores 100 at 2 cm and 0 at 1 cm") {
  const auto truth = sample_strands(grid(5), 100000, 100, 1), shifted = sample_strands(grid(5, 1.5), 100000, 100, 1);
  const auto scores = match_scores(shifted, truth, {{1, 20}, {2, 20}}, 1.0);
  CHECK(fscore(scores, 2, true) == doctest::Approx(100));
  CHECK(fscore(scores, 1, true) == doctest::Approx(0));
  // The scale converts scene units to cm: at 0.5 cm per unit the shift is 0.75 cm.
  CHECK(fscore(match_scores(shifted, truth, {{1, 20}}, 0.5), 1, true) == doctest::Approx(100));
}

TEST_CASE("reversed strands fail the directed angle test and pass the undirected one") {
  const auto truth = sample_strands(grid(5), 100000, 100, 1), reversed = sample_strands(grid(5, 0, true), 100000, 100, 1);
  const auto scores = match_scores(reversed, truth, {{2, 20}}, 1.0);
  CHECK(fscore(scores, 2, true) == doctest::Approx(0));
  CHECK(fscore(scores, 2, false) == doctest::Approx(100));
}

TEST_CASE("straight strands have zero curvature and direction variance") {
  const auto m = consistency_metrics(sample_strands(grid(5), 100000, 100, 1), 1.0);
  CHECK(m.length_mean_cm == doctest::Approx(5));
  CHECK(m.length_std_cm == doctest::Approx(0).epsilon(1e-9));
  CHECK(m.curvature_var_global == doctest::Approx(0).epsilon(1e-9));
  CHECK(m.curvature_var_local == doctest::Approx(0).epsilon(1e-9));
  CHECK(m.max_bending_deg < 0.05);  // float coordinates
  CHECK(m.direction_var_local == doctest::Approx(0).epsilon(1e-9));
  CHECK(m.first_direction_var_local == doctest::Approx(0).epsilon(1e-9));
}

TEST_CASE("known lengths give the exact mean and standard deviation, in cm") {
  // Strands of 1, 2, ..., 10 units in a row, at 2 cm per unit.
  std::vector<float> xyz;
  for (int i = 0; i < 10; ++i)
    for (int p = 0; p < 11; ++p) xyz.insert(xyz.end(), {float(100 * i), float((i + 1) * p / 10.0), 0.f});
  const auto m = consistency_metrics(sample_strands(io::StrandSet::uniform(10, 11, xyz), 1000, 50, 1), 2.0);
  CHECK(m.length_mean_cm == doctest::Approx(11.0));
  CHECK(m.length_std_cm == doctest::Approx(2.0 * std::sqrt(8.25)).epsilon(1e-6));
}

TEST_CASE("a bent strand reports its bending angle and a nonzero curvature variance") {
  io::StrandSet s = grid(5);
  // Bend the first strand by 90 degrees halfway: its second half runs along +x.
  for (std::uint32_t p = 10; p < 20; ++p) {
    s.points[3 * p] = float((p - 9) * 5.0 / 19.0);
    s.points[3 * p + 1] = float(9 * 5.0 / 19.0);
  }
  const auto m = consistency_metrics(sample_strands(s, 1000, 20, 1), 1.0);
  CHECK(m.max_bending_deg == doctest::Approx(90).epsilon(0.01));
  CHECK(m.curvature_var_global > 0);
  CHECK(m.curvature_var_local > 0);
}

TEST_CASE("results do not depend on the order of the strands") {
  io::StrandSet a = grid(5);
  for (std::uint32_t i = 0; i < 144; ++i)
    for (std::uint32_t p = 0; p < 20; ++p) a.points[3 * (i * 20 + p) + 1] *= float(1.0 + 0.01 * (i % 7));  // varied lengths
  io::StrandSet b;
  std::vector<std::uint32_t> order(144);
  for (std::uint32_t i = 0; i < 144; ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), std::mt19937(3));
  std::vector<float> xyz;
  for (std::uint32_t i : order) xyz.insert(xyz.end(), a.points.begin() + i * 60, a.points.begin() + (i + 1) * 60);
  b = io::StrandSet::uniform(144, 20, xyz);
  const auto ma = consistency_metrics(sample_strands(a, 1000, 20, 1), 1.0);
  const auto mb = consistency_metrics(sample_strands(b, 1000, 20, 1), 1.0);
  CHECK(ma.length_mean_cm == doctest::Approx(mb.length_mean_cm));
  CHECK(ma.local_length_std_cm == doctest::Approx(mb.local_length_std_cm));
  CHECK(ma.direction_var_local == doctest::Approx(mb.direction_var_local));
  const auto truth = sample_strands(grid(5, 1.0), 1000, 20, 1);
  const auto sa = match_scores(sample_strands(a, 1000, 20, 1), truth, default_thresholds(), 1.0);
  const auto sb = match_scores(sample_strands(b, 1000, 20, 1), truth, default_thresholds(), 1.0);
  for (std::size_t t = 0; t < sa.size(); ++t) CHECK(sa[t].fscore == doctest::Approx(sb[t].fscore));
}

TEST_CASE("resampling keeps a strand's shape and length whatever its point count") {
  io::StrandSet s;
  s.offsets = {0, 3};
  s.points = {0, 0, 0, 0, 3, 0, 4, 3, 0};  // 3 then 4 long: 7 in all
  const auto r = sample_strands(s, 10, 8, 1);
  REQUIRE(r.strands == 1);
  CHECK(r.xyz[3 * 7] == doctest::Approx(4));
  CHECK(r.xyz[3 * 7 + 1] == doctest::Approx(3));
  CHECK(consistency_metrics(r, 1.0).length_mean_cm == doctest::Approx(7));
}
