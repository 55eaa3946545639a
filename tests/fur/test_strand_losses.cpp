// The geometric strand losses (engine/fur/strand_losses.*): each term's value on strands whose
// answer is known, a fur-stage-sized batch against the reference, refusals. Their gradients are in
// the gradcheck catalog (test_gradcheck).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include <glm/glm.hpp>

#include "engine/core/error.hpp"
#include "engine/fur/strand_losses.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::fur;

namespace {

// A plane SDF: the body is z < 0, on a 5^3 grid over [-1, 1]^3.
struct Plane {
  SdfGridRef grid{{5, 5, 5}, {-1, -1, -1}, 0.5};
  std::vector<float> values;
  Plane() {
    for (int k = 0; k < 5; ++k)
      for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 5; ++i) values.push_back(-1.f + 0.5f * float(k));
  }
};

// A straight strand from `root` along `dir`, L points, `length` long.
void straight(std::vector<float>& points, glm::vec3 root, glm::vec3 dir, std::uint32_t L, float length) {
  for (std::uint32_t k = 0; k < L; ++k) {
    const glm::vec3 p = root + dir * (length * float(k) / float(L - 1));
    points.insert(points.end(), {p.x, p.y, p.z});
  }
}

}  // namespace

TEST_CASE("strand losses: growth direction, curvature consistency and penetration on known strands") {
  const Plane plane;
  const std::uint32_t L = 11;
  std::vector<float> points;
  straight(points, {0, 0, 0.2f}, {0, 0, 1}, L, 0.5f);   // along its guide, above the plane
  straight(points, {0.1f, 0, 0.9f}, {0, 0, -1}, L, 0.5f);  // against its guide, above the plane
  const std::vector<float> guides{0, 0, 1, 0, 0, 1}, lengths{0.5f, 0.5f};
  const StrandLossShape shape{2, L};
  auto l = strand_losses(test::context(), shape, plane.grid, points, guides, lengths, plane.values);
  // Direction: only the second strand, every segment against: sum_l l/S / S over 2 strands.
  const double S = L - 1;
  CHECK(l[0] == doctest::Approx((S - 1) / (2 * S) / 2).epsilon(1e-5));
  CHECK(l[1] == doctest::Approx(0.0).scale(1e-6));  // both straight: the same curvature
  CHECK(l[2] == doctest::Approx(0.0));              // nothing below z = 0

  // Sunk 0.3 below the plane: every point of both strands 0.3 deep on average more.
  std::vector<float> sunk = points;
  for (std::size_t i = 2; i < sunk.size(); i += 3) sunk[i] -= 1.2f;  // z from [0.2, 0.9] to [-1.0, -0.3]
  l = strand_losses(test::context(), shape, plane.grid, sunk, guides, lengths, plane.values);
  double depth = 0;
  for (std::size_t i = 2; i < sunk.size(); i += 3) depth += std::max(0.f, -std::max(sunk[i], -1.f));
  CHECK(l[2] == doctest::Approx(depth / (2 * L)).epsilon(1e-5));

  // One strand bent at its middle: both deviate from the batch mean by half its bend.
  std::vector<float> bent;
  straight(bent, {0, 0, 0.2f}, {0, 0, 1}, L, 0.5f);
  for (std::uint32_t k = 6; k < L; ++k) bent[3 * k] += 0.05f * float(k - 5);  // turns towards +x after point 5
  straight(bent, {0.1f, 0, 0.2f}, {0, 0, 1}, L, 0.5f);
  l = strand_losses(test::context(), shape, plane.grid, bent, guides, lengths, plane.values);
  const double angle = std::atan2(0.05, 0.05);  // the turn at point 5: from +z to 45 degrees
  CHECK(l[1] == doctest::Approx(2 * (angle / 2) * (angle / 2) / (2 * (L - 2))).epsilon(1e-3));
}

TEST_CASE("strand losses: a fur-stage batch (15,000 strands of 100 points) matches the reference; gradients finite") {
  const Plane plane;
  const StrandLossShape shape{15000, 100};
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::vector<float> points, guides, lengths;
  for (std::uint32_t s = 0; s < shape.strands; ++s) {
    glm::vec3 p(0.8f * u(rng), 0.8f * u(rng), 0.05f * u(rng)), d(u(rng), u(rng), 1.f);
    for (std::uint32_t k = 0; k < 100; ++k) {
      points.insert(points.end(), {p.x, p.y, p.z});
      d += 0.2f * glm::vec3(u(rng), u(rng), u(rng));
      p += 0.003f * glm::normalize(d);
    }
    const glm::vec3 g = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
    guides.insert(guides.end(), {g.x, g.y, g.z});
    lengths.push_back(0.3f);
  }
  const auto gpu = strand_losses(test::context(), shape, plane.grid, points, guides, lengths, plane.values);
  const auto ref = strand_losses_ref<double>(std::vector<double>(points.begin(), points.end()), std::vector<double>(guides.begin(), guides.end()),
                                             std::vector<double>(lengths.begin(), lengths.end()), plane.grid,
                                             std::vector<double>(plane.values.begin(), plane.values.end()), shape);
  for (int t = 0; t < 3; ++t) CHECK(gpu[std::size_t(t)] == doctest::Approx(ref[std::size_t(t)]).epsilon(1e-4));
  CHECK(gpu[2] > 0.0);  // some points sink below the plane
  const std::vector<float> grad = strand_losses_gradient(test::context(), shape, plane.grid, points, guides, lengths, plane.values, {});
  CHECK(std::count_if(grad.begin(), grad.end(), [](float g) { return !std::isfinite(g); }) == 0);
}

TEST_CASE("strand losses refuse bad batches, naming them") {
  const Plane plane;
  const StrandLossShape two{1, 2};
  CHECK_THROWS_WITH_AS(strand_losses(test::context(), two, plane.grid, std::vector<float>(6), std::vector<float>(3), std::vector<float>(1), plane.values),
                       doctest::Contains("at least 3 points"), InputError);
  const StrandLossShape shape{1, 3};
  std::vector<float> points(9, 0.1f);
  points[4] = std::nanf("");
  CHECK_THROWS_WITH_AS(strand_losses(test::context(), shape, plane.grid, points, std::vector<float>(3), std::vector<float>(1), plane.values),
                       doctest::Contains("strand points"), InputError);
  CHECK_THROWS_WITH_AS(strand_losses(test::context(), shape, plane.grid, std::vector<float>(9), std::vector<float>(3), std::vector<float>(1),
                                     std::vector<float>(10)),
                       doctest::Contains("SDF grid"), InputError);
}

TEST_CASE("strand losses: the curvature mean holds over 100000 strands (past lavapipe's loop limit)") {
  const Plane plane;
  const StrandLossShape shape{100000, 4};
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::vector<float> points, guides, lengths;
  for (std::uint32_t s = 0; s < shape.strands; ++s) {
    glm::vec3 p(0.5f * u(rng), 0.5f * u(rng), 0.5f), d(0, 0, 1);
    for (std::uint32_t k = 0; k < 4; ++k) {
      points.insert(points.end(), {p.x, p.y, p.z});
      d = glm::normalize(d + (s < 50000 ? 0.05f : 0.6f) * glm::vec3(u(rng), u(rng), 0.f));  // two populations
      p += 0.01f * d;
    }
    guides.insert(guides.end(), {0.f, 0.f, 1.f});
    lengths.push_back(0.03f);
  }
  const auto gpu = strand_losses(test::context(), shape, plane.grid, points, guides, lengths, plane.values);
  const auto ref = strand_losses_ref<double>(std::vector<double>(points.begin(), points.end()), std::vector<double>(guides.begin(), guides.end()),
                                             std::vector<double>(lengths.begin(), lengths.end()), plane.grid,
                                             std::vector<double>(plane.values.begin(), plane.values.end()), shape);
  CHECK(gpu[1] == doctest::Approx(ref[1]).epsilon(1e-3));
}
