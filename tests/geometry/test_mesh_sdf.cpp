// Mesh -> signed distance grid (geometry/mesh_sdf.hpp): the sign on shapes that defeat the nearest
// normal (overlapping parts, holes, thin fins, inverted and duplicated faces), the banded distance
// against analytic distances, and the closest-point routine.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "engine/core/error.hpp"
#include "engine/geometry/closest_point.hpp"
#include "engine/geometry/mesh_sdf.hpp"
#include "tests/support/analytic_meshes.hpp"

using namespace nf;
using namespace nf::geometry;

namespace {

// Compares the grid's sign with the analytic one at every sample farther than `margin` voxels from
// the analytic surface; returns the number of disagreements.
template <class F>
std::size_t sign_mismatches(const SignedDistanceGrid& g, F sdf, double margin) {
  std::size_t bad = 0;
  for (int k = 0; k < g.grid.dims.z; ++k)
    for (int j = 0; j < g.grid.dims.y; ++j)
      for (int i = 0; i < g.grid.dims.x; ++i) {
        const double truth = sdf(glm::dvec3(g.grid.position(i, j, k)));
        if (std::abs(truth) < margin * g.grid.voxel) continue;
        bad += (truth < 0) != (g.distance[g.grid.index(i, j, k)] < 0);
      }
  return bad;
}

}  // namespace

TEST_CASE("closest point on a triangle: interior, edges, corners and degenerate triangles") {
  const glm::vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  auto r = closest_point_on_triangle({0.2f, 0.3f, 2.f}, a, b, c);
  CHECK(glm::length(r.point - glm::vec3(0.2f, 0.3f, 0.f)) < 1e-6f);
  CHECK(r.barycentric.x == doctest::Approx(0.5f));
  r = closest_point_on_triangle({-1.f, -1.f, 0.f}, a, b, c);
  CHECK(glm::length(r.point - a) < 1e-6f);
  r = closest_point_on_triangle({1.f, 1.f, 0.f}, a, b, c);  // beyond the hypotenuse
  CHECK(glm::length(r.point - glm::vec3(0.5f, 0.5f, 0.f)) < 1e-6f);
  r = closest_point_on_triangle({2.f, 0.5f, 0.f}, a, b, b);  // a segment
  CHECK(glm::length(r.point - b) < 1e-6f);
  r = closest_point_on_triangle({0.5f, 1.f, 0.f}, a, a, a);  // a point
  CHECK(glm::length(r.point - a) < 1e-6f);
  // Random points: the result is on the triangle and no random point of it is closer.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-2.f, 2.f), w(0.f, 1.f);
  for (int trial = 0; trial < 200; ++trial) {
    const glm::vec3 p(u(rng), u(rng), u(rng)), q0(u(rng), u(rng), u(rng)), q1(u(rng), u(rng), u(rng)), q2(u(rng), u(rng), u(rng));
    const auto cp = closest_point_on_triangle(p, q0, q1, q2);
    CHECK(std::abs(cp.barycentric.x + cp.barycentric.y + cp.barycentric.z - 1.f) < 1e-5f);
    CHECK(glm::length(cp.point - (cp.barycentric.x * q0 + cp.barycentric.y * q1 + cp.barycentric.z * q2)) < 1e-4f);
    const float best = glm::length(p - cp.point);
    for (int s = 0; s < 50; ++s) {
      float x = w(rng), y = w(rng);
      if (x + y > 1) x = 1 - x, y = 1 - y;
      CHECK(glm::length(p - (q0 + x * (q1 - q0) + y * (q2 - q0))) >= best - 1e-4f);
    }
  }
}

TEST_CASE("SDF of a sphere: exact distance in the band, sign everywhere, clamped beyond") {
  const auto sdf = [](glm::dvec3 p) { return test::sphere_sdf(p, {0, 0, 0}, 0.8); };
  const Mesh sphere = test::mesh_of(sdf, 1.0, 0.02);
  SdfOptions o;
  o.resolution = 40;
  const SignedDistanceGrid g = signed_distance_grid(sphere, o, "sphere");
  CHECK(g.band == doctest::Approx(3 * g.grid.voxel));
  CHECK(sign_mismatches(g, sdf, 0.1) == 0);
  CHECK(g.sign.open_lines == 0);
  double worst = 0;
  for (int k = 0; k < g.grid.dims.z; ++k)
    for (int j = 0; j < g.grid.dims.y; ++j)
      for (int i = 0; i < g.grid.dims.x; ++i) {
        const double truth = sdf(glm::dvec3(g.grid.position(i, j, k)));
        const float d = g.distance[g.grid.index(i, j, k)];
        if (std::abs(truth) < g.band - g.grid.voxel) worst = std::max(worst, std::abs(d - truth));
        else if (std::abs(truth) > g.band + g.grid.voxel) CHECK(std::abs(d) == doctest::Approx(g.band));
      }
  CHECK(worst < 0.002);  // the marching-cubes sphere itself is within ~0.1 % of the radius
  CHECK(sample_grid(g.grid, g.distance, {0.f, 0.f, 0.79f}) == doctest::Approx(-0.01).epsilon(0.2));
}

TEST_CASE("SDF sign: a torus, two overlapping spheres, an inverted sphere") {
  SdfOptions o;
  o.resolution = 48;
  const auto torus = [](glm::dvec3 p) { return test::torus_sdf(p, 0.6, 0.2); };
  CHECK(sign_mismatches(signed_distance_grid(test::mesh_of(torus, 1.0, 0.02), o, "torus"), torus, 0.5) == 0);

  // Two closed spheres that overlap, as two meshes: the overlap has winding number 2 (inside);
  // parity, or the nearest normal (which points out of the other sphere), would get it wrong.
  const auto a = [](glm::dvec3 p) { return test::sphere_sdf(p, {-0.3, 0, 0}, 0.5); };
  const auto b = [](glm::dvec3 p) { return test::sphere_sdf(p, {0.3, 0.05, 0}, 0.5); };
  const Mesh both = test::concatenate(test::mesh_of(a, 1.0, 0.025), test::mesh_of(b, 1.0, 0.025));
  const auto either = [&](glm::dvec3 p) { return std::min(a(p), b(p)); };
  const SignedDistanceGrid g = signed_distance_grid(both, o, "two spheres");
  CHECK(sign_mismatches(g, either, 0.5) == 0);
  CHECK(g.distance[g.grid.index(g.grid.dims.x / 2, g.grid.dims.y / 2, g.grid.dims.z / 2)] < 0);  // inside both

  // Touching at one point (one sphere's surface meets the other's).
  const auto c = [](glm::dvec3 p) { return test::sphere_sdf(p, {0.5, 0, 0}, 0.5); };
  const auto d = [](glm::dvec3 p) { return test::sphere_sdf(p, {-0.5, 0, 0}, 0.5); };
  const Mesh touching = test::concatenate(test::mesh_of(c, 1.2, 0.025), test::mesh_of(d, 1.2, 0.025));
  CHECK(sign_mismatches(signed_distance_grid(touching, o, "touching"), [&](glm::dvec3 p) { return std::min(c(p), d(p)); }, 0.5) == 0);

  // Inside-out faces: the winding number is -1 inside, still inside.
  Mesh inverted = test::mesh_of(a, 1.0, 0.025);
  for (std::size_t t = 0; t < inverted.triangle_count(); ++t) std::swap(inverted.triangles[3 * t + 1], inverted.triangles[3 * t + 2]);
  CHECK(sign_mismatches(signed_distance_grid(inverted, o, "inverted"), a, 0.5) == 0);
}

TEST_CASE("SDF sign survives holes, duplicated faces and a stray internal face") {
  const auto sdf = [](glm::dvec3 p) { return test::sphere_sdf(p, {0, 0, 0}, 0.7); };
  Mesh m = test::mesh_of(sdf, 1.0, 0.02);
  // A hole: every face with a vertex near the top pole goes (a cap of radius ~0.1).
  Mesh holed = m;
  holed.triangles.clear();
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    bool near_pole = false;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = m.triangles[3 * t + std::size_t(k)];
      const glm::dvec3 p(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
      near_pole |= glm::length(p - glm::dvec3(0, 0.7, 0)) < 0.1;
    }
    if (!near_pole) holed.triangles.insert(holed.triangles.end(), m.triangles.begin() + std::ptrdiff_t(3 * t), m.triangles.begin() + std::ptrdiff_t(3 * t + 3));
  }
  SdfOptions o;
  o.resolution = 48;
  const SignedDistanceGrid g = signed_distance_grid(holed, o, "holed sphere");
  CHECK(g.sign.open_lines > 0);  // the lines through the hole do not vote
  CHECK(sign_mismatches(g, sdf, 0.5) == 0);

  // Duplicated faces and a stray face inside: their lines do not close and are outvoted.
  Mesh messy = m;
  for (std::size_t t = 0; t < 200; ++t) messy.triangles.insert(messy.triangles.end(), m.triangles.begin() + std::ptrdiff_t(3 * t), m.triangles.begin() + std::ptrdiff_t(3 * t + 3));
  const std::uint32_t base = std::uint32_t(messy.vertex_count());
  messy.positions.insert(messy.positions.end(), {-0.3f, 0.f, -0.3f, 0.3f, 0.f, -0.3f, 0.f, 0.f, 0.3f});
  messy.triangles.insert(messy.triangles.end(), {base, base + 1, base + 2});
  messy.normals.clear();
  CHECK(sign_mismatches(signed_distance_grid(messy, o, "messy sphere"), sdf, 0.5) == 0);
}

TEST_CASE("SDF sign of a thin ear-like fin thinner than a voxel") {
  // A ball with a fin 0.02 thick (under half a grid voxel) standing out of it.
  const auto fin = [](glm::dvec3 p) {
    const glm::dvec3 q = glm::abs(p - glm::dvec3(0, 0.55, 0)) - glm::dvec3(0.25, 0.3, 0.01);
    const double box = glm::length(glm::max(q, 0.0)) + std::min(std::max({q.x, q.y, q.z}), 0.0);
    return std::min(test::sphere_sdf(p, {0, 0, 0}, 0.4), box);
  };
  const Mesh m = test::mesh_of(fin, 1.0, 0.004);
  SdfOptions o;
  o.resolution = 28;  // voxel about 0.045: the fin is under half a voxel thick
  const SignedDistanceGrid g = signed_distance_grid(m, o, "fin");
  CHECK(g.grid.voxel > 2 * 0.02);
  CHECK(sign_mismatches(g, fin, 0.3) == 0);
  // Beside the fin: outside and close.
  const float beside = sample_grid(g.grid, g.distance, {0.f, 0.7f, 0.05f});
  CHECK(beside > 0.f);
  CHECK(beside < 0.06f);
}

TEST_CASE("SDF input errors name the mesh") {
  Mesh empty;
  CHECK_THROWS_WITH_AS(signed_distance_grid(empty, {}, "M.ply"), doctest::Contains("M.ply"), InputError);
  Mesh bad = test::mesh_of([](glm::dvec3 p) { return test::sphere_sdf(p, {0, 0, 0}, 0.5); }, 1.0, 0.1);
  bad.positions[4] = std::nanf("");
  CHECK_THROWS_WITH_AS(signed_distance_grid(bad, {}, "M.ply"), doctest::Contains("M.ply"), InputError);
  CHECK_THROWS_AS(grid_around({0, 0, 0}, {0, 0, 0}, 10, 0), InputError);
}
