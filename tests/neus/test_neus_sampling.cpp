// Sample placement along rays for the NeuS trainer (engine/neus/ray_sampling.hpp): occupied
// segments from the DDA, stratified samples over segments with gaps, NeuS up-sampling around a
// known zero crossing, and merged sections that tile the sampled stretches.
#include <doctest/doctest.h>

#include <cmath>
#include <numeric>

#include "engine/neus/ray_sampling.hpp"

using namespace nf;

TEST_CASE("occupied segments: adjacent cells merge, a gap splits, the sphere bounds them") {
  neus::OccupancyGrid g;
  g.lo = glm::dvec3(-0.5), g.hi = glm::dvec3(0.5), g.dims = glm::ivec3(10);
  g.occupied.assign(g.cell_count(), 0);
  for (int i = 1; i <= 3; ++i) g.occupied[g.index(i, 5, 5)] = 1;  // x in [-0.4, -0.1]
  for (int i = 6; i <= 7; ++i) g.occupied[g.index(i, 5, 5)] = 1;  // x in [0.1, 0.3]
  const neus::Normalisation identity;
  const auto s = neus::occupied_segments({-2.0, 0.05, 0.05}, {1.0, 0.0, 0.0}, identity, g, 1e-3);
  REQUIRE(s.size() == 2);
  CHECK(s[0].near == doctest::Approx(1.6));
  CHECK(s[0].far == doctest::Approx(1.9));
  CHECK(s[1].near == doctest::Approx(2.1));
  CHECK(s[1].far == doctest::Approx(2.3));
  CHECK(neus::occupied_segments({-2.0, 0.45, 0.45}, {1.0, 0.0, 0.0}, identity, g, 1e-3).empty());
}

TEST_CASE("stratified samples cover segments end to end, none in the gap") {
  std::vector<float> t, dist;
  neus::stratified_samples({{1.f, 2.f}, {3.f, 3.5f}}, 6, 0.5f, t, dist);
  REQUIRE(t.size() == 6);
  for (const float x : t) CHECK(((x >= 1.f && x <= 2.f) || (x >= 3.f && x <= 3.5f)));
  CHECK(std::count_if(t.begin(), t.end(), [](float x) { return x < 2.5f; }) == 4);  // 2/3 of the length
  CHECK(std::accumulate(dist.begin(), dist.end(), 0.f) == doctest::Approx(1.5f));
  neus::stratified_samples({}, 6, 0.5f, t, dist);
  CHECK(t.empty());
}

TEST_CASE("NeuS up-sampling puts the fine samples at the zero crossing") {
  std::vector<float> t, sdf;
  for (int i = 0; i < 32; ++i) {
    t.push_back(0.5f + i / 32.f);
    sdf.push_back(1.1f - t.back());  // crosses zero at t = 1.1, entering the surface
  }
  const auto fine = neus::upsample_positions(t, sdf, 0.05f, 128.f, 16, 0.5f);
  REQUIRE(fine.size() == 16);
  CHECK(std::is_sorted(fine.begin(), fine.end()));
  int near_surface = 0;
  for (const float x : fine) near_surface += std::fabs(x - 1.1f) < 0.06f;
  CHECK(near_surface >= 14);
  // An interval longer than max_gap (a gap between segments) gets nothing.
  std::vector<float> gapped = t;
  for (std::size_t i = 16; i < gapped.size(); ++i) gapped[i] += 1.f;  // the crossing falls in the gap
  for (const float x : neus::upsample_positions(gapped, sdf, 0.05f, 128.f, 16, 0.5f))
    CHECK(!(x > t[15] + 1e-6f && x < gapped[16] - 1e-6f));
  CHECK(neus::upsample_positions({1.f}, {0.f}, 0.1f, 64.f, 8, 0.5f).empty());
}

TEST_CASE("merged samples: sections tile each stretch and stop at gaps") {
  std::vector<float> t, dist;
  neus::merge_samples({1.05f, 1.15f, 1.25f}, {1.1f, 1.12f}, 0.1f, t, dist);
  REQUIRE(t.size() == 5);
  CHECK(std::is_sorted(t.begin(), t.end()));
  CHECK(std::accumulate(dist.begin(), dist.end(), 0.f) == doctest::Approx(0.3f));  // [1.0, 1.3]
  neus::merge_samples({1.f, 5.f}, {}, 0.1f, t, dist);  // far apart: each keeps max_section
  CHECK(dist[0] == doctest::Approx(0.1f));
  CHECK(dist[1] == doctest::Approx(0.1f));
}
