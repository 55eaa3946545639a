// The one-way chamfer (engine/fur/strand_chamfer.*): the grid search finds exactly the brute-force
// nearest points (ties to the lowest index) on coarse, fine and sparse grids and for points outside
// the grid, and leaves unmatched exactly the queries beyond its reach; the fur stage's choice of
// grid and its loop budget; a point nearest to thousands of queries; the adjoint accumulating or
// overwriting; refusals. Its gradients are in the gradcheck catalog.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>

#include "engine/core/error.hpp"
#include "engine/fur/strand_chamfer.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::fur;

TEST_CASE("strand chamfer: the grid search finds the brute-force nearest point, within its reach") {
  const std::vector<float> queries = test::random_f32(3 * 300, 1, -1.2f, 1.2f);  // some outside the grid
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
  // The fur stage's grid: cells from the shell's area (about 100 points a cell), an eighth of the box's reach.
  const ChamferGrid grid = chamfer_grid_for(glm::vec3(-0.6f), glm::vec3(0.6f), 1500000, 4.0 * 3.14159265358979 * 0.25, 1.2 / 8);
  CHECK(grid.dims[0] == 83);  // ceil(1.2 / sqrt(100 pi / 1.5e6))
  CHECK(grid.reach() >= 1.2 / 8);
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

TEST_CASE("strand chamfer: ties go to the lowest index, whichever cell walls the query sits on") {
  // A lattice of points (every value exact in binary) in shuffled order, queries on the lattice's
  // cell centres, faces and edges: 8, 4 or 2 points at exactly the same distance, found across
  // grid cells whose walls pass through, beside or between them.
  std::vector<glm::vec3> lattice;
  for (int x = -4; x <= 4; ++x)
    for (int y = -4; y <= 4; ++y)
      for (int z = -4; z <= 4; ++z) lattice.push_back(0.25f * glm::vec3(x, y, z));
  std::shuffle(lattice.begin(), lattice.end(), std::mt19937(9));
  std::vector<float> points, queries;
  for (const glm::vec3& p : lattice) points.insert(points.end(), {p.x, p.y, p.z});
  for (int x = -3; x <= 3; ++x)
    for (int y = -3; y <= 3; ++y)
      for (const glm::vec3 off : {glm::vec3(0.125f), glm::vec3(0.125f, 0.125f, 0.f), glm::vec3(0.125f, 0.f, 0.f)})
        queries.insert(queries.end(), {0.25f * float(x) + off.x, 0.25f * float(y) + off.y, 0.25f * float(((x + y) % 3 + 3) % 3 - 1) + off.z});
  for (const int cells : {2, 8, 16, 24}) {
    CAPTURE(cells);
    const ChamferGrid grid = chamfer_grid(glm::vec3(-1.f), glm::vec3(1.f), cells);
    CHECK(strand_chamfer_nearest(test::context(), grid, queries, points) == nearest_points_ref(queries, points, grid.reach()));
  }
}

TEST_CASE("strand chamfer: a point nearest to thousands of queries gets their whole gradient") {
  // 10,000 queries around one point: its run of the sorted queries spans several of the adjoint's
  // 4,096-query chunks.
  const std::vector<float> points{0.f, 0.f, 0.f, 0.9f, 0.9f, 0.9f, -0.9f, 0.9f, 0.f};
  const std::vector<float> queries = test::random_f32(3 * 10000, 4, 0.05f, 0.15f);
  const ChamferGrid grid = chamfer_grid(glm::vec3(-1.f), glm::vec3(1.f), 16);
  const std::vector<float> grad = strand_chamfer_gradient(test::context(), grid, queries, points, 3.0);
  const std::vector<double> ref = strand_chamfer_backward_ref(std::vector<double>(queries.begin(), queries.end()),
                                                              std::vector<double>(points.begin(), points.end()), grid.reach(), 3.0);
  REQUIRE(grad.size() == ref.size());
  for (std::size_t i = 0; i < grad.size(); ++i) CHECK(grad[i] == doctest::Approx(ref[i]).epsilon(1e-3));
  for (std::size_t i = 3; i < grad.size(); ++i) CHECK(grad[i] == 0.f);
}

TEST_CASE("strand chamfer: the fur stage's grid keeps its reach within lavapipe's loop budget") {
  // Dense points on a small fur would ask for 256 cells; the reach (an eighth of the box) then needs
  // 32 rings, past what one invocation may loop on lavapipe: the grid takes fewer cells instead.
  const ChamferGrid grid = chamfer_grid_for(glm::vec3(-1.f), glm::vec3(1.f), 50000000, 0.01, 2.0 / 8);
  CHECK(grid.max_rings == kMaxChamferRings);
  CHECK(grid.dims[0] == 96);
  CHECK(grid.reach() == doctest::Approx(2.0 / 8));
  // A query just inside the reach walks all 12 rings of empty cells and finds the one point; one
  // just outside is unmatched.
  const std::vector<float> points{0.01f, 0.02f, 0.03f};
  const float r = float(grid.reach());
  const std::vector<float> queries{0.01f + 0.98f * r, 0.02f, 0.03f, 0.01f, 0.02f - 0.98f * r * 0.7071f, 0.03f + 0.98f * r * 0.7071f,
                                   0.01f + 1.02f * r, 0.02f, 0.03f};
  const std::vector<std::uint32_t> nn = strand_chamfer_nearest(test::context(), grid, queries, points);
  CHECK(nn == std::vector<std::uint32_t>{0, 0, kUnmatched});
  ChamferGrid deeper = grid;
  deeper.max_rings = kMaxChamferRings + 1;
  CHECK_THROWS_WITH_AS(strand_chamfer_nearest(test::context(), deeper, queries, points), doctest::Contains("rings"), InputError);
}

TEST_CASE("strand chamfer: the adjoint adds to a gradient when asked and overwrites it otherwise") {
  const std::vector<float> points = test::random_f32(3 * 500, 6, -1.f, 1.f), queries = test::random_f32(3 * 200, 7, -1.f, 1.f);
  const ChamferGrid grid = chamfer_grid(glm::vec3(-1.f), glm::vec3(1.f), 8);
  const std::vector<double> ref = strand_chamfer_backward_ref(std::vector<double>(queries.begin(), queries.end()),
                                                              std::vector<double>(points.begin(), points.end()), grid.reach(), 2.0);
  gpu::Buffer<float> d_points(test::context(), points, "points"), d_queries(test::context(), queries, "queries");
  StrandChamferScratch scratch(test::context(), 500, 200, grid);
  for (const bool accumulate : {false, true}) {
    CAPTURE(accumulate);
    // One element past the points' gradient: the adjoint must not touch it.
    gpu::Buffer<float> grad(test::context(), std::vector<float>(points.size() + 1, 0.5f), "gradient");
    gpu::Stream stream(test::context());
    strand_chamfer_forward(stream, grid, d_queries, d_points, scratch);
    strand_chamfer_backward(stream, d_queries, d_points, scratch, 2.0, grad, accumulate);
    stream.submit_and_wait();
    const std::vector<float> g = grad.download();
    for (std::size_t i = 0; i < points.size(); ++i) CHECK(g[i] == doctest::Approx(ref[i] + (accumulate ? 0.5 : 0.0)).epsilon(1e-5));
    CHECK(g.back() == 0.5f);
  }
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
  CHECK_THROWS_WITH_AS(StrandChamferScratch(test::context(), 10, kMaxChamferQueries + 1, grid), doctest::Contains("fur.chamfer_queries"), InputError);
}

