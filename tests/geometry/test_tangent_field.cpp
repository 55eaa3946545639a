// Smooth tangent fields (geometry/tangent_field.hpp), mesh repair and decimation
// (geometry/mesh_repair.hpp), and per-vertex smoothing (geometry/vertex_smoothing.hpp).
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/core/error.hpp"
#include "engine/geometry/mesh_repair.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/geometry/tangent_field.hpp"
#include "engine/geometry/vertex_smoothing.hpp"
#include "tests/support/analytic_meshes.hpp"

using namespace nf;
using namespace nf::geometry;

namespace {

// An n x n grid of squares in the xz plane (y up), split into triangles with alternating diagonals.
Mesh plane(int n, double size) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.positions.insert(m.positions.end(), {float(size * i / n), 0.f, float(size * j / n)});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::uint32_t a = std::uint32_t(j * (n + 1) + i), b = a + 1, c = a + std::uint32_t(n + 1), d = c + 1;
      if ((i + j) % 2) m.triangles.insert(m.triangles.end(), {a, c, b, b, c, d});
      else m.triangles.insert(m.triangles.end(), {a, c, d, a, d, b});
    }
  return m;
}

glm::vec3 centroid(const Mesh& m, std::size_t f) {
  glm::vec3 c(0.f);
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t v = m.triangles[3 * f + std::size_t(k)];
    c += glm::vec3(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
  }
  return c / 3.f;
}

double angle_deg(glm::vec3 a, glm::vec3 b) {
  return std::acos(std::clamp(double(glm::dot(glm::normalize(a), glm::normalize(b))), -1.0, 1.0)) * 180.0 / 3.14159265358979;
}

}  // namespace

TEST_CASE("tangent field on a plane follows a constant guide exactly") {
  const Mesh m = plane(20, 1.0);
  std::vector<glm::vec3> guides(m.triangle_count(), glm::normalize(glm::vec3(1.f, 0.3f, 0.5f)));  // leans out of the plane
  const TangentField f = smooth_tangent_field(m, guides, {0.1, 40});
  CHECK(f.guided_faces == m.triangle_count());
  const glm::vec3 expected = glm::normalize(glm::vec3(1.f, 0.f, 0.5f));
  for (std::size_t i = 0; i < m.triangle_count(); ++i) {
    CHECK(angle_deg(f.tangent[i], expected) < 0.01);
    CHECK(std::abs(glm::dot(f.tangent[i], f.normal[i])) < 1e-5f);
    CHECK(std::abs(glm::length(f.tangent[i]) - 1.f) < 1e-5f);
  }
  const FieldSmoothness s = field_smoothness(m, f.tangent);
  CHECK(s.mean_angle_deg < 0.01);
  CHECK(s.flipped_edges == 0);
}

TEST_CASE("tangent field: two guides meet in a smooth turn whose width follows the smoothing length") {
  const Mesh m = plane(40, 1.0);
  std::vector<glm::vec3> guides(m.triangle_count());
  for (std::size_t i = 0; i < guides.size(); ++i) guides[i] = centroid(m, i).x < 0.5f ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1);
  // The guides jump by 90 degrees; the field turns gradually, more gradually with a longer length.
  double mean_short = 0, mean_long = 0;
  for (double length : {0.02, 0.1}) {
    const TangentField f = smooth_tangent_field(m, guides, {length, 40});
    const FieldSmoothness s = field_smoothness(m, f.tangent);
    CHECK(s.flipped_edges == 0);
    (length < 0.05 ? mean_short : mean_long) = s.mean_angle_deg;
    // Far from the border, each side keeps its guide.
    for (std::size_t i = 0; i < guides.size(); ++i) {
      const float x = centroid(m, i).x;
      if (std::abs(x - 0.5f) > 6 * length) CHECK(angle_deg(f.tangent[i], guides[i]) < 5.0);
    }
    // The turn is monotone across the border: the angle to +x grows with x along a row.
  }
  CHECK(mean_long < mean_short);
}

TEST_CASE("tangent field: without guides, the smoothest field on a sphere; the same field in any frame and unit") {
  const Mesh sphere = test::mesh_of([](glm::dvec3 p) { return test::sphere_sdf(p, {0, 0, 0}, 0.7); }, 1.0, 0.07);
  const std::vector<glm::vec3> none(sphere.triangle_count(), glm::vec3(0.f));
  const TangentField f = smooth_tangent_field(sphere, none);
  CHECK(f.guided_faces == 0);
  for (std::size_t i = 0; i < f.tangent.size(); ++i) {
    CHECK(std::abs(glm::length(f.tangent[i]) - 1.f) < 1e-4f);
    CHECK(std::abs(glm::dot(f.tangent[i], f.normal[i])) < 1e-4f);
  }
  const FieldSmoothness s = field_smoothness(sphere, f.tangent);
  // A sphere must have singularities (index sum 2), so a few edges turn sharply; the rest is smooth.
  CHECK(s.mean_angle_deg < 6.0);
  CHECK(s.flipped_edges < s.edges / 100);

  // Guided by "down" (y-), rotated and scaled to a z-up frame in centimetres: the same field, rotated.
  std::vector<glm::vec3> down(sphere.triangle_count(), glm::vec3(0, -1, 0));
  const TangentField a = smooth_tangent_field(sphere, down, {0.05, 40});
  const glm::mat4 R = glm::rotate(glm::mat4(1.f), 1.5707963f, glm::vec3(1, 0, 0));  // y up -> z up
  Mesh moved = sphere;
  for (std::size_t v = 0; v < moved.vertex_count(); ++v) {
    const glm::vec3 p = 100.f * glm::vec3(R * glm::vec4(sphere.positions[3 * v], sphere.positions[3 * v + 1], sphere.positions[3 * v + 2], 1.f));
    for (int c = 0; c < 3; ++c) moved.positions[3 * v + std::size_t(c)] = p[c];
  }
  std::vector<glm::vec3> moved_down(sphere.triangle_count(), glm::vec3(R * glm::vec4(0, -1, 0, 0)));
  const TangentField b = smooth_tangent_field(moved, moved_down, {5.0, 40});
  double worst = 0, to_guide = 0;
  std::size_t counted = 0;
  for (std::size_t i = 0; i < a.tangent.size(); ++i) {
    worst = std::max(worst, angle_deg(glm::vec3(R * glm::vec4(a.tangent[i], 0.f)), b.tangent[i]));
    const glm::vec3 n = a.normal[i], g = glm::vec3(0, -1, 0) - glm::dot(glm::vec3(0, -1, 0), n) * n;
    if (glm::length(g) > 0.5f) to_guide += angle_deg(a.tangent[i], g), ++counted;  // away from the poles
  }
  CHECK(worst < 0.1);
  CHECK(to_guide / double(counted) < 5.0);
}

TEST_CASE("tangent field input errors") {
  const Mesh m = plane(2, 1.0);
  CHECK_THROWS_AS(smooth_tangent_field(m, std::vector<glm::vec3>(3)), InputError);
  std::vector<glm::vec3> bad(m.triangle_count(), glm::vec3(1, 0, 0));
  bad[1].x = std::nanf("");
  CHECK_THROWS_WITH_AS(smooth_tangent_field(m, bad), doctest::Contains("face 1"), InputError);
}

TEST_CASE("repair: degenerate, duplicated and non-manifold faces go, small holes close, the largest part stays") {
  Mesh m = test::mesh_of([](glm::dvec3 p) { return test::sphere_sdf(p, {0, 0, 0}, 0.6); }, 1.0, 0.05);
  REQUIRE(is_closed_manifold(m));
  const std::size_t faces = m.triangle_count();
  Mesh broken = m;
  // A hole of one face, a duplicate, a degenerate face, a fin on an existing edge, a far speck.
  broken.triangles.erase(broken.triangles.begin(), broken.triangles.begin() + 3);
  broken.triangles.insert(broken.triangles.end(), m.triangles.begin() + 30, m.triangles.begin() + 33);
  broken.triangles.insert(broken.triangles.end(), {m.triangles[40], m.triangles[40], m.triangles[41]});
  const std::uint32_t v = std::uint32_t(broken.vertex_count());
  broken.positions.insert(broken.positions.end(), {0.f, 0.f, 0.f, 5.f, 5.f, 5.f, 5.1f, 5.f, 5.f, 5.f, 5.1f, 5.f});
  broken.triangles.insert(broken.triangles.end(), {m.triangles[60], m.triangles[61], v});
  broken.triangles.insert(broken.triangles.end(), {v + 1, v + 2, v + 3});
  broken.normals.clear();
  const RepairReport r = repair_mesh(broken, 100);
  CHECK(r.degenerate_faces >= 1);  // ours, and the marching cubes' zero-area faces at grid corners
  CHECK(r.duplicate_faces == 1);
  CHECK(r.non_manifold_faces == 3);  // the fin and the two faces of the edge it hangs on
  CHECK(r.holes_filled >= 2);
  CHECK(r.components_dropped == 1);
  CHECK(is_closed_manifold(broken));
  CHECK(broken.triangle_count() >= faces - 2);
}

TEST_CASE("decimation reaches the face budget and stays on the surface; smoothing keeps fixed vertices") {
  Mesh m = test::mesh_of([](glm::dvec3 p) { return test::sphere_sdf(p, {0, 0, 0}, 0.6); }, 1.0, 0.02);
  m.regions.assign(m.vertex_count(), 3);
  const Bounds box = mesh_bounds(m);  // the sphere's box, and the empty mesh's
  for (int a = 0; a < 3; ++a) CHECK((box.lo[a] == doctest::Approx(-0.6f).epsilon(0.01) && box.hi[a] == doctest::Approx(0.6f).epsilon(0.01)));
  CHECK(box.longest() == doctest::Approx(1.2f).epsilon(0.01));
  CHECK(box.diagonal() == doctest::Approx(1.2f * std::sqrt(3.f)).epsilon(0.01));
  CHECK(m.position(7) == glm::vec3(m.positions[21], m.positions[22], m.positions[23]));
  CHECK(mesh_bounds(Mesh{}).diagonal() == 0.f);
  const std::size_t before = m.triangle_count();
  const DecimateReport d = decimate(m, before / 4);
  CHECK(d.faces_after <= before / 4 + 10);
  CHECK(d.faces_after > before / 5);
  CHECK(m.regions.size() == m.vertex_count());
  repair_mesh(m, 100);  // edge collapses may pinch a vertex or fold a sliver; the repair after them closes it
  CHECK(is_closed_manifold(m));
  for (std::size_t v = 0; v < m.vertex_count(); ++v)
    CHECK(std::abs(glm::length(glm::vec3(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2])) - 0.6f) < 0.01f);
  CHECK(decimate(m, 10 * before).faces_after == m.triangle_count());  // under budget: unchanged

  // Smoothing a step: values spread, the fixed vertex stays, the mean of a closed mesh is kept.
  std::vector<float> values(m.vertex_count());
  std::vector<std::uint8_t> active(m.vertex_count(), 1);
  for (std::size_t v = 0; v < values.size(); ++v) values[v] = m.positions[3 * v] > 0 ? 1.f : 0.f;
  active[0] = 0;
  const float fixed = values[0];
  smooth_vertex_values(m, values, 1, 30, active);
  CHECK(values[0] == fixed);
  const auto nb = vertex_neighbours(m);
  float max_step = 0;
  for (std::size_t v = 1; v < values.size(); ++v)
    for (std::uint32_t n : nb[v])
      if (n != 0) max_step = std::max(max_step, std::abs(values[v] - values[n]));
  CHECK(max_step < 0.2f);
}
