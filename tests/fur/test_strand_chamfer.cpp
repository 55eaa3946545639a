// The one-way chamfer (engine/fur/strand_chamfer.*): the grid search finds exactly the brute-force
// nearest points (ties to the lowest index) on coarse, fine and sparse grids and for points outside
// the grid, and leaves unmatched exactly the queries beyond its reach; refusals. Its gradients are
// in the gradcheck catalog.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>

#include "engine/core/error.hpp"
#include "engine/fur/strand_chamfer.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::fur;

TEST_CASE("strand chamfer: the grid search finds the brute-force nearest point, within its reach") {
  const std::vector<float> queries = test::random_f32(3 * 300, 1, -1.f, 1.f);
  for (const int cells : {1, 4, 16, 64, 256}) {
    CAPTURE(cells);
    for (const std::size_t count : {std::size_t(5), std::size_t(3000)}) {
      CAPTURE(count);
      const std::vector<float> points = test::random_f32(3 * count, 2, -1.3f, 1.3f);  // some outside the grid
      const ChamferGrid grid = chamfer_grid(glm::vec3(-1.f), glm::vec3(1.f), cells);
      const std::vector<std::uint32_t> nn = strand_chamfer_nearest(test::context(), grid, queries, points);
      const std::vector<std::uint32_t> ref = nearest_points_ref(queries, points, grid.reach());
      CHECK(nn == ref);
      const ChamferValue v = strand_chamfer(test::context(), grid, queries, points);
      CHECK(v.loss == doctest::Approx(strand_chamfer_ref(queries, points, grid.reach())).epsilon(1e-5));
      CHECK(v.unmatched == std::uint64_t(std::count(ref.begin(), ref.end(), kUnmatched)));
      if (cells <= 4) CHECK(v.unmatched == 0);  // the reach (8 cells) covers the whole box
    }
  }
}

TEST_CASE("strand chamfer: a fur-stage batch (1.5 M strand points, 20,000 queries) is exact where the reference can tell") {
  // Points on a sphere's shell (strands near the skin), queries on a slightly larger sphere.
  std::mt19937 rng(5);
  std::normal_distribution<float> n(0.f, 1.f);
  const auto on_sphere = [&](std::size_t count, float radius) {
    std::vector<float> v;
    for (std::size_t i = 0; i < count; ++i) {
      glm::vec3 p(n(rng), n(rng), n(rng));
      p = radius * glm::normalize(p);
      v.insert(v.end(), {p.x, p.y, p.z});
    }
    return v;
  };
  const std::vector<float> points = on_sphere(1500000, 0.5f), queries = on_sphere(20000, 0.52f);
  const ChamferGrid grid = chamfer_grid(glm::vec3(-0.6f), glm::vec3(0.6f), 64);
  const std::vector<std::uint32_t> nn = strand_chamfer_nearest(test::context(), grid, queries, points);
  // The brute force on a sample of the queries.
  for (std::size_t k = 0; k < 20000; k += 997) {
    const std::vector<float> q(queries.begin() + std::ptrdiff_t(3 * k), queries.begin() + std::ptrdiff_t(3 * k + 3));
    CHECK(nn[k] == nearest_points_ref(q, points, grid.reach())[0]);
  }
  CHECK(std::count(nn.begin(), nn.end(), kUnmatched) == 0);
  const std::vector<float> grad = strand_chamfer_gradient(test::context(), grid, queries, points, 20.0);
  std::size_t pulled = 0;
  for (std::size_t j = 0; j < grad.size(); j += 3) pulled += grad[j] != 0.f || grad[j + 1] != 0.f || grad[j + 2] != 0.f;
  CHECK(pulled > 0);
  CHECK(pulled <= 20000);
}

TEST_CASE("strand chamfer refuses empty, non-finite and badly shaped input") {
  const ChamferGrid grid = chamfer_grid(glm::vec3(-1.f), glm::vec3(1.f), 8);
  CHECK_THROWS_AS(strand_chamfer(test::context(), grid, std::vector<float>(3), std::vector<float>()), InputError);
  CHECK_THROWS_WITH_AS(strand_chamfer(test::context(), grid, std::vector<float>(3), std::vector<float>(4)), doctest::Contains("triples"), InputError);
  std::vector<float> points(6, 0.f);
  points[2] = std::nanf("");
  CHECK_THROWS_WITH_AS(strand_chamfer(test::context(), grid, std::vector<float>(3), points), doctest::Contains("strand points"), InputError);
  CHECK_THROWS_AS(chamfer_grid(glm::vec3(0.f), glm::vec3(0.f), 8), InputError);
  CHECK_THROWS_AS(chamfer_grid(glm::vec3(0.f), glm::vec3(1.f), 0), InputError);
}
