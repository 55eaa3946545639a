// Marching cubes (generated case table, welded extraction), mesh tools and the distance transform.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/geometry/distance_transform.hpp"
#include "engine/geometry/marching_cubes.hpp"
#include "engine/geometry/marching_cubes_table.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "tests/support/scalar_grid.hpp"

using namespace nf;
using namespace nf::geometry;

namespace {

constexpr double kPi = 3.14159265358979323846;

using Grid = test::ScalarGrid;

geometry::Mesh extract(const Grid& g, float iso = 0.f) { return marching_cubes(g.values.data(), g.dims, g.origin, g.h, iso); }

glm::dvec3 position(const geometry::Mesh& m, std::uint32_t v) {
  return {m.positions[3 * std::size_t(v)], m.positions[3 * std::size_t(v) + 1], m.positions[3 * std::size_t(v) + 2]};
}
glm::dvec3 normal(const geometry::Mesh& m, std::uint32_t v) {
  return {m.normals[3 * std::size_t(v)], m.normals[3 * std::size_t(v) + 1], m.normals[3 * std::size_t(v) + 2]};
}
glm::dvec3 face_cross(const geometry::Mesh& m, std::size_t t) {  // 2 * area * unit normal
  const glm::dvec3 p0 = position(m, m.triangles[3 * t]);
  return glm::cross(position(m, m.triangles[3 * t + 1]) - p0, position(m, m.triangles[3 * t + 2]) - p0);
}

long long euler_characteristic(const geometry::Mesh& m) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (std::size_t t = 0; t < m.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = m.triangles[3 * t + k], b = m.triangles[3 * t + (k + 1) % 3];
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  return (long long)m.vertex_count() - (long long)edges.size() + (long long)m.triangle_count();
}

double area(const geometry::Mesh& m) {
  double a = 0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) a += 0.5 * glm::length(face_cross(m, t));
  return a;
}

double signed_volume(const geometry::Mesh& m) {  // divergence theorem; positive for outward-facing triangles
  double v = 0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t)
    v += glm::dot(position(m, m.triangles[3 * t]),
                  glm::cross(position(m, m.triangles[3 * t + 1]), position(m, m.triangles[3 * t + 2]))) / 6;
  return v;
}

// Whether cube edges a and b lie on a common face: all four corners agree on one axis bit.
bool share_face(const MarchingCubesTable& t, int a, int b) {
  for (int axis = 0; axis < 3; ++axis) {
    int bits = 0;
    for (int c : {t.edge_corners[a][0], t.edge_corners[a][1], t.edge_corners[b][0], t.edge_corners[b][1]})
      bits |= 1 << ((c >> axis) & 1);
    if (bits != 3) return true;
  }
  return false;
}

// The directed edges of a case's triangles that no other triangle of the case uses.
std::set<std::pair<int, int>> boundary_chords(const MarchingCubesTable& t, int cs) {
  std::multiset<std::pair<int, int>> directed;
  for (int i = 0; i < 3 * t.triangle_count[cs]; i += 3)
    for (int k = 0; k < 3; ++k) directed.insert({t.triangles[cs][i + k], t.triangles[cs][i + (k + 1) % 3]});
  std::set<std::pair<int, int>> out;
  for (const auto& [a, b] : directed)
    if (!directed.count({b, a})) out.insert({a, b});
  return out;
}

}  // namespace

TEST_CASE("the generated table: every case closes into a surface whose boundary lies on the cube's faces") {
  const MarchingCubesTable& t = marching_cubes_table();
  int most = 0;
  for (int cs = 0; cs < 256; ++cs) {
    CAPTURE(cs);
    const int n = t.triangle_count[cs];
    most = std::max(most, n);
    REQUIRE(n <= kMcMaxTriangles);
    for (int i = 0; i < kMcRowLength; ++i) CHECK((t.triangles[cs][i] >= 0) == (i < 3 * n));
    // The vertices used are exactly the sign-changing edges.
    std::uint16_t used = 0;
    for (int i = 0; i < 3 * n; ++i) used = std::uint16_t(used | (1u << t.triangles[cs][i]));
    std::uint16_t crossing = 0;
    for (int e = 0; e < 12; ++e)
      if (((cs >> t.edge_corners[e][0]) & 1) != ((cs >> t.edge_corners[e][1]) & 1)) crossing = std::uint16_t(crossing | (1u << e));
    CHECK(used == crossing);
    CHECK(t.edge_mask[cs] == crossing);
    // Inside the case every edge is used once or twice; twice means once each way (oriented), and
    // the edges used once (the boundary) join two vertices on one face and form closed loops.
    std::map<std::pair<int, int>, int> uses;
    for (int i = 0; i < 3 * n; i += 3) {
      CHECK(t.triangles[cs][i] != t.triangles[cs][i + 1]);
      for (int k = 0; k < 3; ++k) {
        const int a = t.triangles[cs][i + k], b = t.triangles[cs][i + (k + 1) % 3];
        ++uses[{a, b}];
      }
    }
    for (const auto& [edge, count] : uses) CHECK(count == 1);  // no directed edge twice
    const auto chords = boundary_chords(t, cs);
    std::map<int, int> out_degree, in_degree;
    for (const auto& [a, b] : chords) {
      CHECK(share_face(t, a, b));
      ++out_degree[a];
      ++in_degree[b];
    }
    for (int e = 0; e < 12; ++e)
      if ((crossing >> e) & 1) CHECK((out_degree[e] == 1 && in_degree[e] == 1));
    // Interior edges (used both ways) never join two vertices on a common face.
    for (const auto& [edge, count] : uses)
      if (uses.count({edge.second, edge.first})) CHECK_FALSE(share_face(t, edge.first, edge.second));
  }
  CHECK(most == 5);
  CHECK(t.triangle_count[0] == 0);
  CHECK(t.triangle_count[255] == 0);
}

TEST_CASE("the generated table: two cubes sharing a face trace the same chords on it, in opposite directions") {
  const MarchingCubesTable& t = marching_cubes_table();
  auto edge_between = [&](int c0, int c1) {
    for (int e = 0; e < 12; ++e)
      if ((t.edge_corners[e][0] == c0 && t.edge_corners[e][1] == c1) || (t.edge_corners[e][0] == c1 && t.edge_corners[e][1] == c0))
        return e;
    return -1;
  };
  auto on_face = [&](int e, int axis, int side) {
    return ((t.edge_corners[e][0] >> axis) & 1) == side && ((t.edge_corners[e][1] >> axis) & 1) == side;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int cs = 0; cs < 256; ++cs) {
      // The neighbour on the +axis side: its corners with bit `axis` = 0 are this cube's with 1.
      int other = 0;
      for (int c = 0; c < 8; ++c)
        if ((cs >> (c | (1 << axis))) & 1) other |= 1 << c;
      std::set<std::pair<int, int>> mine, theirs;
      for (const auto& [a, b] : boundary_chords(t, cs))
        if (on_face(a, axis, 1) && on_face(b, axis, 1)) mine.insert({a, b});
      for (const auto& [a, b] : boundary_chords(t, other))
        if (on_face(a, axis, 0) && on_face(b, axis, 0)) {
          const int ma = edge_between(t.edge_corners[a][0] | (1 << axis), t.edge_corners[a][1] | (1 << axis));
          const int mb = edge_between(t.edge_corners[b][0] | (1 << axis), t.edge_corners[b][1] | (1 << axis));
          theirs.insert({mb, ma});  // reversed
        }
      CAPTURE(axis);
      CAPTURE(cs);
      CHECK(mine == theirs);
    }
}

TEST_CASE("a sphere: closed manifold of genus 0, accurate area, volume, positions and normals") {
  const glm::dvec3 c(0.031, -0.017, 0.009);
  const double r = 0.7;
  const int n = 64;
  const float h = 2.f / float(n - 1);
  const Grid g = test::sample_grid({n, n, n}, glm::vec3(-1.f), glm::vec3(h), [&](glm::dvec3 p) { return glm::length(p - c) - r; });
  geometry::Mesh m = extract(g);
  REQUIRE(m.triangle_count() > 0);
  CHECK_NOTHROW(m.validate("sphere"));
  CHECK(is_closed_manifold(m));
  CHECK(euler_characteristic(m) == 2);

  const double area_error = area(m) / (4 * kPi * r * r) - 1, volume_error = signed_volume(m) / (4 * kPi * r * r * r / 3) - 1;
  double max_distance = 0, min_vertex_dot = 1, min_face_dot = 1, weighted_face_dot = 0, total = 0;
  for (std::uint32_t v = 0; v < m.vertex_count(); ++v) {
    const glm::dvec3 d = position(m, v) - c;
    max_distance = std::max(max_distance, std::abs(glm::length(d) - r));
    min_vertex_dot = std::min(min_vertex_dot, glm::dot(normal(m, v), glm::normalize(d)));
  }
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const glm::dvec3 x = face_cross(m, t);
    const glm::dvec3 centre =
        (position(m, m.triangles[3 * t]) + position(m, m.triangles[3 * t + 1]) + position(m, m.triangles[3 * t + 2])) / 3.0;
    const double len = glm::length(x), dot = glm::dot(x, glm::normalize(centre - c));
    if (len > 0) min_face_dot = std::min(min_face_dot, dot / len);
    weighted_face_dot += dot;
    total += len;
  }
  MESSAGE("sphere 64^3: " << m.vertex_count() << " vertices, " << m.triangle_count() << " triangles, area error "
                          << area_error << ", volume error " << volume_error << ", max |dist| " << max_distance / h
                          << " voxel, min vertex-normal dot " << min_vertex_dot << ", min face dot " << min_face_dot
                          << ", area-weighted face dot " << weighted_face_dot / total);
  // Measured: area -0.064 %, volume -0.12 %, 0.0057 voxel, dots 1.0 / 0.9995 / 0.99994.
  CHECK(std::abs(area_error) < 0.002);
  CHECK(std::abs(volume_error) < 0.003);
  CHECK(max_distance < 0.02 * h);
  CHECK(min_vertex_dot > 0.999);
  CHECK(min_face_dot > 0.99);  // every triangle faces outward
  CHECK(weighted_face_dot / total > 0.999);

  // Area-weighted normals of the extracted mesh agree with the analytic ones too.
  geometry::Mesh recomputed = m;
  compute_vertex_normals(recomputed);
  double min_recomputed_dot = 1;
  for (std::uint32_t v = 0; v < m.vertex_count(); ++v)
    min_recomputed_dot = std::min(min_recomputed_dot, glm::dot(normal(recomputed, v), glm::normalize(position(m, v) - c)));
  MESSAGE("area-weighted vertex normals: min dot " << min_recomputed_dot);
  CHECK(min_recomputed_dot > 0.998);  // measured 0.99925

  CHECK(keep_largest_component(m) == 1);
  CHECK(m.triangle_count() == recomputed.triangle_count());
}

TEST_CASE("a sphere on an anisotropic grid, and the iso-value shifts the surface") {
  const glm::vec3 h(0.045f, 0.03f, 0.02f);
  const glm::ivec3 dims(45, 67, 101);  // about [-1, 1]^3
  const double r = 0.6;
  const Grid g = test::sample_grid(dims, glm::vec3(-1.f), h, [&](glm::dvec3 p) { return glm::length(p) - r; });
  for (float iso : {0.f, 0.15f}) {
    const geometry::Mesh m = extract(g, iso);
    CHECK(is_closed_manifold(m));
    CHECK(euler_characteristic(m) == 2);
    const double R = r + iso, volume_error = signed_volume(m) / (4 * kPi * R * R * R / 3) - 1;
    double max_distance = 0, min_dot = 1;
    for (std::uint32_t v = 0; v < m.vertex_count(); ++v) {
      max_distance = std::max(max_distance, std::abs(glm::length(position(m, v)) - R));
      min_dot = std::min(min_dot, glm::dot(normal(m, v), glm::normalize(position(m, v))));
    }
    MESSAGE("anisotropic sphere, iso " << iso << ": volume error " << volume_error << ", max |dist| " << max_distance
                                       << ", min normal dot " << min_dot);
    CHECK(std::abs(volume_error) < 0.004);  // measured 0.18 %, 0.00042 (a fifth of the smallest voxel / 10)
    CHECK(max_distance < 0.001);
    CHECK(min_dot > 0.999);
  }
}

TEST_CASE("a torus has Euler characteristic 0") {
  const double R = 0.6, r = 0.22;
  const int n = 64;
  const Grid g = test::sample_grid({n, n, n}, glm::vec3(-1.f), glm::vec3(2.f / float(n - 1)), [&](glm::dvec3 p) { return test::torus_sdf(p, R, r); });
  const geometry::Mesh m = extract(g);
  CHECK(is_closed_manifold(m));
  CHECK(euler_characteristic(m) == 0);
  const double volume_error = signed_volume(m) / (2 * kPi * kPi * R * r * r) - 1, area_error = area(m) / (4 * kPi * kPi * R * r) - 1;
  MESSAGE("torus 64^3: volume error " << volume_error << ", area error " << area_error);
  CHECK(std::abs(volume_error) < 0.008);  // measured -0.43 %
  CHECK(std::abs(area_error) < 0.003);    // measured -0.12 %
}

TEST_CASE("two disjoint spheres: keep_largest_component keeps the bigger one, with its regions and normals") {
  const glm::dvec3 big(-0.45, 0.05, 0), small(0.6, -0.1, 0.1);
  const double rb = 0.45, rs = 0.3;
  const int n = 64;
  const float h = 2.f / float(n - 1);
  const Grid g = test::sample_grid({n, n, n}, glm::vec3(-1.f), glm::vec3(h), [&](glm::dvec3 p) {
    return std::min(glm::length(p - big) - rb, glm::length(p - small) - rs);
  });
  geometry::Mesh m = extract(g);
  CHECK(is_closed_manifold(m));
  CHECK(euler_characteristic(m) == 4);
  // Regions: 1 on the big sphere's vertices, 2 on the small one's.
  for (std::uint32_t v = 0; v < m.vertex_count(); ++v) m.regions.push_back(position(m, v).x < 0.1 ? 1 : 2);
  const auto before = m.vertex_count();
  CHECK(keep_largest_component(m) == 2);
  CHECK(m.vertex_count() < before);
  CHECK_NOTHROW(m.validate("largest component"));
  CHECK(m.normals.size() == m.positions.size());
  CHECK(is_closed_manifold(m));
  CHECK(euler_characteristic(m) == 2);
  double max_distance = 0, min_dot = 1;
  for (std::uint32_t v = 0; v < m.vertex_count(); ++v) {
    max_distance = std::max(max_distance, std::abs(glm::length(position(m, v) - big) - rb));
    min_dot = std::min(min_dot, glm::dot(normal(m, v), glm::normalize(position(m, v) - big)));
    CHECK(m.regions[v] == 1);
  }
  CHECK(max_distance < 0.1 * h);
  CHECK(min_dot > 0.99);
  CHECK(signed_volume(m) == doctest::Approx(4 * kPi * rb * rb * rb / 3).epsilon(0.01));
}

TEST_CASE("random noise padded with outside values: always a closed, outward-facing manifold") {
  const int n = 24;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> uniform(-1.f, 1.f);
    std::uniform_int_distribution<int> level(-1, 1);
    const bool quantised = seed > 3;  // samples exactly on the iso-value too
    std::vector<float> values(std::size_t(n) * n * n);
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const bool border = x == 0 || y == 0 || z == 0 || x == n - 1 || y == n - 1 || z == n - 1;
          values[x + n * (y + n * z)] = border ? 1.f : quantised ? float(level(rng)) : uniform(rng);
        }
    for (float iso : {0.f, -0.4f, 0.4f}) {
      if (quantised && iso != 0.f) continue;
      CAPTURE(seed);
      CAPTURE(iso);
      const geometry::Mesh m = marching_cubes(values.data(), {n, n, n}, glm::vec3(0.f), glm::vec3(1.f), iso);
      CHECK(m.triangle_count() > 1000);
      CHECK(is_closed_manifold(m));
      CHECK(signed_volume(m) > 0);
      CHECK_NOTHROW(m.validate("noise"));
    }
    // Without the padding the surface is cut open at the border.
    std::vector<float> open = values;
    for (int i = 0; i < n * n; ++i) open[std::size_t(i)] = -1.f;  // the z = 0 layer inside
    CHECK_FALSE(is_closed_manifold(marching_cubes(open.data(), {n, n, n}, glm::vec3(0.f), glm::vec3(1.f))));
  }
}

TEST_CASE("marching cubes: bad input is rejected, degenerate grids give empty meshes") {
  std::vector<float> v(27, 1.f);
  v[13] = -1.f;
  CHECK(marching_cubes(v.data(), {3, 3, 3}, glm::vec3(0.f), glm::vec3(1.f)).triangle_count() == 8);  // an octahedron
  CHECK(is_closed_manifold(marching_cubes(v.data(), {3, 3, 3}, glm::vec3(0.f), glm::vec3(1.f))));
  CHECK(marching_cubes(v.data(), {27, 1, 1}, glm::vec3(0.f), glm::vec3(1.f)).triangle_count() == 0);
  CHECK(marching_cubes(nullptr, {0, 0, 0}, glm::vec3(0.f), glm::vec3(1.f)).vertex_count() == 0);
  v[4] = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_AS(marching_cubes(v.data(), {3, 3, 3}, glm::vec3(0.f), glm::vec3(1.f)), InputError);
  v[4] = std::numeric_limits<float>::infinity();
  CHECK_THROWS_AS(marching_cubes(v.data(), {3, 3, 3}, glm::vec3(0.f), glm::vec3(1.f)), InputError);
  v[4] = 1.f;
  CHECK_THROWS_AS(marching_cubes(v.data(), {3, 3, 3}, glm::vec3(0.f), glm::vec3(1.f, 0.f, 1.f)), InputError);
  CHECK_THROWS_AS(marching_cubes(v.data(), {3, -3, 3}, glm::vec3(0.f), glm::vec3(1.f)), InputError);
  CHECK_THROWS_AS(marching_cubes(v.data(), {3, 3, 3}, glm::vec3(0.f), glm::vec3(1.f), std::nanf("")), InputError);
}

TEST_CASE("mesh tools on small meshes") {
  // Two disjoint tetrahedra, the second with more triangles (a split face).
  geometry::Mesh m;
  m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1,  // tetrahedron A
                 5, 0, 0, 6, 0, 0, 5, 1, 0, 5, 0, 1, 5.25f, 0.25f, 0};  // tetrahedron B, vertex 8 splits a face
  m.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3,  // outward
                 4, 6, 8, 4, 8, 5, 6, 5, 8, 4, 5, 7, 4, 7, 6, 5, 6, 7};
  CHECK(is_closed_manifold(m));
  CHECK(euler_characteristic(m) == 4);
  compute_vertex_normals(m);
  CHECK(glm::dot(normal(m, 0), glm::normalize(glm::dvec3(-1, -1, -1))) == doctest::Approx(1.0));
  geometry::Mesh flipped = m;
  std::swap(flipped.triangles[0], flipped.triangles[1]);
  CHECK_FALSE(is_closed_manifold(flipped));
  geometry::Mesh open = m;
  open.triangles.resize(open.triangles.size() - 3);
  CHECK_FALSE(is_closed_manifold(open));
  geometry::Mesh pinched;  // two tetrahedra sharing one vertex: edges fine, vertex not a disk
  pinched.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1};
  pinched.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 0, 4, 5, 0, 6, 4, 0, 5, 6, 4, 6, 5};
  CHECK_FALSE(is_closed_manifold(pinched));

  m.regions = {0, 0, 0, 0, 7, 7, 7, 7, 9};
  m.positions.insert(m.positions.end(), {9, 9, 9});  // an unused vertex
  m.normals.insert(m.normals.end(), {0, 0, 1});
  m.regions.push_back(3);
  CHECK(keep_largest_component(m) == 2);
  CHECK(m.vertex_count() == 5);
  CHECK(m.triangle_count() == 6);
  CHECK(m.regions == std::vector<std::int32_t>{7, 7, 7, 7, 9});
  CHECK(m.positions[0] == 5.f);
  CHECK(m.normals.size() == 15);
  CHECK(is_closed_manifold(m));

  geometry::Mesh empty;
  empty.positions = {1, 2, 3};
  CHECK(keep_largest_component(empty) == 0);
  CHECK(empty.vertex_count() == 0);
  CHECK(is_closed_manifold(empty));
}

TEST_CASE("distance transform: exact against brute force on an anisotropic grid") {
  const glm::ivec3 dims(20, 17, 13);
  const glm::vec3 h(0.7f, 1.3f, 0.45f);
  for (double density : {0.002, 0.03, 0.3}) {
    std::mt19937 rng(7);
    std::bernoulli_distribution feature(density);
    std::vector<std::uint8_t> mask(std::size_t(dims.x) * dims.y * dims.z);
    std::vector<glm::dvec3> features;
    for (int z = 0, i = 0; z < dims.z; ++z)
      for (int y = 0; y < dims.y; ++y)
        for (int x = 0; x < dims.x; ++x, ++i)
          if (feature(rng)) {
            mask[std::size_t(i)] = 1;
            features.push_back(glm::dvec3(x, y, z) * glm::dvec3(h));
          }
    REQUIRE(!features.empty());
    const std::vector<float> d = distance_transform(mask, dims, h);
    REQUIRE(d.size() == mask.size());
    double worst = 0;
    for (int z = 0, i = 0; z < dims.z; ++z)
      for (int y = 0; y < dims.y; ++y)
        for (int x = 0; x < dims.x; ++x, ++i) {
          double best = std::numeric_limits<double>::infinity();
          for (const auto& f : features) best = std::min(best, glm::length(glm::dvec3(x, y, z) * glm::dvec3(h) - f));
          worst = std::max(worst, std::abs(double(d[std::size_t(i)]) - best));
          if (mask[std::size_t(i)]) CHECK(d[std::size_t(i)] == 0.f);
        }
    CAPTURE(density);
    CHECK(worst < 1e-5);
  }
}

TEST_CASE("distance transform: empty, full and invalid masks") {
  const glm::ivec3 dims(5, 4, 3);
  std::vector<std::uint8_t> mask(60, 0);
  for (float v : distance_transform(mask, dims, glm::vec3(0.5f))) CHECK(std::isinf(v));
  std::fill(mask.begin(), mask.end(), 1);
  for (float v : distance_transform(mask, dims)) CHECK(v == 0.f);
  std::fill(mask.begin(), mask.end(), 0);
  mask[0] = 1;
  const auto d = distance_transform(mask, dims, glm::vec3(1.f, 2.f, 3.f));
  CHECK(d.back() == doctest::Approx(std::sqrt(16.0 + 36.0 + 36.0)));
  CHECK(distance_transform({}, {0, 4, 3}).empty());
  CHECK_THROWS_AS(distance_transform(mask, {5, 4, 2}), InputError);
  CHECK_THROWS_AS(distance_transform(mask, dims, glm::vec3(1.f, -1.f, 1.f)), InputError);
}
