// GPU marching cubes against the CPU extractor: the same welded mesh up to the order of vertices and
// triangles (sphere, torus, noise, samples exactly on the iso-value, slabs smaller than the grid),
// closed surfaces, degenerate grids and bad input.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/geometry/marching_cubes.hpp"
#include "engine/geometry/marching_cubes_gpu.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/gpu/buffer.hpp"
#include "tests/support/gpu_test.hpp"
#include "tests/support/scalar_grid.hpp"

using namespace nf;
using namespace nf::geometry;

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

using Grid = test::ScalarGrid;

geometry::Mesh cpu_mesh(const Grid& g, float iso = 0.f) { return marching_cubes(g.values.data(), g.dims, g.origin, g.h, iso); }

geometry::Mesh gpu_mesh(const Grid& g, float iso = 0.f, const MarchingCubesGpuOptions& options = {}) {
  return marching_cubes_gpu(test::context(), g.values, g.dims, g.origin, g.h, iso, options);
}

glm::vec3 position(const geometry::Mesh& m, std::size_t v) {
  return {m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]};
}
glm::vec3 normal(const geometry::Mesh& m, std::size_t v) { return {m.normals[3 * v], m.normals[3 * v + 1], m.normals[3 * v + 2]}; }

// Pairs every GPU vertex with a distinct CPU vertex whose position is within `tol` per coordinate,
// preferring the nearest and, among equal positions (several edges may put their vertex on one grid
// point), the most similar normal. kNone where there is none.
std::vector<std::uint32_t> match_vertices(const geometry::Mesh& got, const geometry::Mesh& cpu, double tol) {
  const double cell = 2 * tol;  // a match lies in one of the 27 cells around
  auto key = [&](glm::vec3 p) {
    return std::array<long long, 3>{(long long)std::floor(double(p.x) / cell), (long long)std::floor(double(p.y) / cell),
                                    (long long)std::floor(double(p.z) / cell)};
  };
  std::map<std::array<long long, 3>, std::vector<std::uint32_t>> buckets;
  for (std::uint32_t v = 0; v < cpu.vertex_count(); ++v) buckets[key(position(cpu, v))].push_back(v);
  std::vector<char> used(cpu.vertex_count(), 0);
  std::vector<std::uint32_t> match(got.vertex_count(), kNone);
  for (std::uint32_t v = 0; v < got.vertex_count(); ++v) {
    const glm::vec3 p = position(got, v), n = normal(got, v);
    const auto k = key(p);
    double best_score = std::numeric_limits<double>::infinity();
    for (long long dz = -1; dz <= 1; ++dz)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dx = -1; dx <= 1; ++dx) {
          const auto it = buckets.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == buckets.end()) continue;
          for (const std::uint32_t c : it->second) {
            if (used[c]) continue;
            const glm::dvec3 d = glm::abs(glm::dvec3(p) - glm::dvec3(position(cpu, c)));
            const double distance = std::max({d.x, d.y, d.z});
            if (distance > tol) continue;
            const double score = distance / tol + (1.0 - glm::dot(glm::dvec3(n), glm::dvec3(normal(cpu, c))));
            if (score < best_score) best_score = score, match[v] = c;
          }
        }
    if (match[v] != kNone) used[match[v]] = 1;
  }
  return match;
}

// Each triangle as its three corner positions (taken from the CPU mesh, through `through` for the
// GPU mesh), rotated to the smallest of its three rotations so the winding is kept; sorted.
std::vector<std::array<float, 9>> triangle_set(const geometry::Mesh& m, const geometry::Mesh& cpu, const std::vector<std::uint32_t>* through) {
  std::vector<std::array<float, 9>> out;
  out.reserve(m.triangle_count());
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    glm::vec3 p[3];
    for (int k = 0; k < 3; ++k) {
      std::uint32_t v = m.triangles[3 * t + std::size_t(k)];
      if (through) v = (*through)[v];
      p[k] = position(cpu, v);
    }
    std::array<float, 9> best{};
    for (int r = 0; r < 3; ++r) {
      std::array<float, 9> rotated{};
      for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) rotated[std::size_t(3 * k + c)] = p[(k + r) % 3][c];
      if (r == 0 || rotated < best) best = rotated;
    }
    out.push_back(best);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The GPU mesh equals the CPU one up to order: counts, every vertex within 1e-5 of the grid's
// coordinate scale, normals (all but `loose_normals` of them with dot > 0.9999), and the triangles
// as oriented position triples.
void check_same_mesh(const geometry::Mesh& got, const geometry::Mesh& cpu, const Grid& g, double loose_normals = 0.0) {
  REQUIRE(got.vertex_count() == cpu.vertex_count());
  REQUIRE(got.triangle_count() == cpu.triangle_count());
  REQUIRE(got.normals.size() == got.positions.size());
  CHECK_NOTHROW(got.validate("gpu marching cubes"));
  const glm::vec3 far = g.origin + glm::vec3(g.dims - 1) * g.h;
  const double scale = std::max({1e-30f, std::abs(g.origin.x), std::abs(g.origin.y), std::abs(g.origin.z), std::abs(far.x),
                                 std::abs(far.y), std::abs(far.z)});
  const std::vector<std::uint32_t> match = match_vertices(got, cpu, 1e-5 * scale);
  const auto unmatched = std::count(match.begin(), match.end(), kNone);
  CHECK(unmatched == 0);
  if (unmatched) return;

  std::size_t loose = 0;
  double min_dot = 1;
  for (std::uint32_t v = 0; v < got.vertex_count(); ++v) {
    const double dot = glm::dot(glm::dvec3(normal(got, v)), glm::dvec3(normal(cpu, match[v])));
    min_dot = std::min(min_dot, dot);
    if (dot < 0.9999) ++loose;
  }
  CAPTURE(min_dot);
  CHECK(double(loose) <= loose_normals * double(got.vertex_count()));
  CHECK(triangle_set(got, cpu, &match) == triangle_set(cpu, cpu, nullptr));
}

Grid sphere_grid(glm::ivec3 dims, glm::vec3 h, glm::dvec3 centre, double r) {
  const glm::vec3 origin = -0.5f * glm::vec3(dims - 1) * h;
  return test::sample_grid(dims, origin, h, [&](glm::dvec3 p) { return glm::length(p - centre) - r; });
}

Grid noise_grid(glm::ivec3 dims, unsigned seed, bool padded, bool quantised) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(-1.f, 1.f);
  std::uniform_int_distribution<int> level(-1, 1);
  Grid g{std::vector<float>(std::size_t(dims.x) * dims.y * dims.z), dims, glm::vec3(0.5f, -2.f, 1.f), glm::vec3(1.f, 0.75f, 1.25f)};
  for (int z = 0, i = 0; z < dims.z; ++z)
    for (int y = 0; y < dims.y; ++y)
      for (int x = 0; x < dims.x; ++x, ++i) {
        const bool border = x == 0 || y == 0 || z == 0 || x == dims.x - 1 || y == dims.y - 1 || z == dims.z - 1;
        g.values[std::size_t(i)] = padded && border ? 1.f : quantised ? float(level(rng)) : uniform(rng);
      }
  return g;
}

}  // namespace

TEST_CASE("gpu marching cubes: a sphere on an anisotropic grid gives the CPU mesh, closed") {
  // Unequal sizes and spacings per axis catch any mix-up of strides or steps.
  const Grid g = sphere_grid({41, 53, 37}, glm::vec3(0.05f, 0.038f, 0.055f), glm::dvec3(0.031, -0.017, 0.009), 0.7);
  for (float iso : {0.f, 0.15f, -0.2f}) {
    CAPTURE(iso);
    const geometry::Mesh cpu = cpu_mesh(g, iso), got = gpu_mesh(g, iso);
    REQUIRE(cpu.triangle_count() > 1000);
    check_same_mesh(got, cpu, g);
    CHECK(is_closed_manifold(got));
    MESSAGE("sphere iso " << iso << ": " << got.vertex_count() << " vertices, " << got.triangle_count() << " triangles");
  }
}

TEST_CASE("gpu marching cubes: a torus gives the CPU mesh, closed") {
  const double R = 0.6, r = 0.22;
  const int n = 56;
  const Grid g = test::sample_grid({n, n, n}, glm::vec3(-1.f), glm::vec3(2.f / float(n - 1)), [&](glm::dvec3 p) { return test::torus_sdf(p, R, r); });
  const geometry::Mesh cpu = cpu_mesh(g), got = gpu_mesh(g);
  REQUIRE(cpu.triangle_count() > 1000);
  check_same_mesh(got, cpu, g);
  CHECK(is_closed_manifold(got));
}

TEST_CASE("gpu marching cubes: random noise, open at the border and padded") {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    CAPTURE(seed);
    const Grid open = noise_grid({19, 23, 17}, seed, false, false);
    for (float iso : {0.f, 0.3f, -0.5f}) {
      CAPTURE(iso);
      const geometry::Mesh cpu = cpu_mesh(open, iso), got = gpu_mesh(open, iso);
      REQUIRE(cpu.triangle_count() > 1000);
      // A generic field's interpolated gradient can nearly cancel; float (GPU) and double (CPU)
      // then disagree on its direction. Rare: at most one vertex in a thousand.
      check_same_mesh(got, cpu, open, 1e-3);
    }
    const Grid padded = noise_grid({24, 21, 22}, seed, true, false);
    const geometry::Mesh cpu = cpu_mesh(padded), got = gpu_mesh(padded);
    check_same_mesh(got, cpu, padded, 1e-3);
    CHECK(is_closed_manifold(got));
  }
}

TEST_CASE("gpu marching cubes: samples exactly on the iso-value count as outside, as on the CPU") {
  // Quantised noise: a third of the samples equal the iso-value 0.
  for (unsigned seed = 4; seed <= 6; ++seed) {
    CAPTURE(seed);
    const Grid q = noise_grid({15, 13, 17}, seed, seed == 6, true);
    const geometry::Mesh cpu = cpu_mesh(q), got = gpu_mesh(q);
    REQUIRE(cpu.triangle_count() > 100);
    check_same_mesh(got, cpu, q);
    if (seed == 6) CHECK(is_closed_manifold(got));
    // iso = 1 equals the largest samples (everything below is inside); iso = -1 leaves nothing inside.
    check_same_mesh(gpu_mesh(q, 1.f), cpu_mesh(q, 1.f), q);
    CHECK(gpu_mesh(q, -1.f).vertex_count() == 0);
  }
  // A smooth field with exact zeros: |p|^2 - 25 on an integer grid (e.g. (3, 4, 0) lies on it).
  const Grid s = test::sample_grid({13, 13, 13}, glm::vec3(-6.f), glm::vec3(1.f), [](glm::dvec3 p) { return glm::dot(p, p) - 25.0; });
  check_same_mesh(gpu_mesh(s), cpu_mesh(s), s);
  CHECK(is_closed_manifold(gpu_mesh(s)));
  // One inside sample in a 3^3 grid: an octahedron.
  std::vector<float> v(27, 1.f);
  v[13] = -1.f;
  const geometry::Mesh octahedron = marching_cubes_gpu(test::context(), v, {3, 3, 3}, glm::vec3(0.f), glm::vec3(1.f));
  CHECK(octahedron.vertex_count() == 6);
  CHECK(octahedron.triangle_count() == 8);
  CHECK(is_closed_manifold(octahedron));
}

TEST_CASE("gpu marching cubes: slabs smaller than the grid, values at an unaligned offset") {
  const Grid g = sphere_grid({33, 29, 41}, glm::vec3(0.05f), glm::dvec3(0.02, -0.03, 0.01), 0.62);
  const geometry::Mesh cpu = cpu_mesh(g);
  REQUIRE(cpu.triangle_count() > 1000);
  auto& ctx = test::context();
  const std::uint64_t count = g.values.size();
  // Three floats in: the bindings must start below the values on the offset alignment.
  gpu::Buffer<float> shifted(ctx, count + 3, "shifted grid values");
  shifted.upload(std::span<const float>(g.values), 3);
  // 26 KiB: one layer per emit slab (two layers of edge ids are 22 KiB); 48 KiB: about three.
  for (std::uint64_t budget : {26u * 1024u, 48u * 1024u, 0u}) {
    CAPTURE(budget);
    MarchingCubesGpuOptions options;
    options.max_binding_bytes = budget;
    check_same_mesh(gpu_mesh(g, 0.f, options), cpu, g);
    const geometry::Mesh offset = marching_cubes_gpu(ctx, shifted.range(3, count), g.dims, g.origin, g.h, 0.f, options);
    check_same_mesh(offset, cpu, g);
    CHECK(is_closed_manifold(offset));
  }
  // Too small for a single layer: refused, naming the limit.
  MarchingCubesGpuOptions tiny;
  tiny.max_binding_bytes = 8 * 1024;
  CHECK_THROWS_WITH_AS(gpu_mesh(g, 0.f, tiny), doctest::Contains("maxStorageBufferRange"), DeviceError);
}

TEST_CASE("gpu marching cubes: empty and thin grids give empty meshes") {
  auto& ctx = test::context();
  CHECK(marching_cubes_gpu(ctx, std::vector<float>{}, {0, 0, 0}, glm::vec3(0.f), glm::vec3(1.f)).vertex_count() == 0);
  CHECK(marching_cubes_gpu(ctx, std::vector<float>{}, {0, 5, 5}, glm::vec3(0.f), glm::vec3(1.f)).vertex_count() == 0);
  const std::vector<float> line(27, -1.f);
  CHECK(marching_cubes_gpu(ctx, line, {27, 1, 1}, glm::vec3(0.f), glm::vec3(1.f)).triangle_count() == 0);
  const Grid sheet = noise_grid({6, 5, 1}, 3, false, false);
  CHECK(marching_cubes_gpu(ctx, sheet.values, sheet.dims, sheet.origin, sheet.h).vertex_count() == 0);
  const Grid column = noise_grid({1, 6, 5}, 3, false, false);
  CHECK(marching_cubes_gpu(ctx, column.values, column.dims, column.origin, column.h).vertex_count() == 0);
  // No crossing at all: every sample outside, or every sample inside.
  for (float fill : {1.f, -1.f}) {
    const std::vector<float> flat(7 * 6 * 5, fill);
    const geometry::Mesh m = marching_cubes_gpu(ctx, flat, {7, 6, 5}, glm::vec3(0.f), glm::vec3(1.f));
    CHECK(m.vertex_count() == 0);
    CHECK(m.triangle_count() == 0);
  }
  // Two layers thick: the thinnest grid with cells.
  const Grid slab = noise_grid({9, 7, 2}, 8, false, false);
  const geometry::Mesh cpu = cpu_mesh(slab);
  REQUIRE(cpu.triangle_count() > 0);
  check_same_mesh(gpu_mesh(slab), cpu, slab, 1e-3);
}

TEST_CASE("gpu marching cubes: NaN and Inf samples are rejected naming the first, bad parameters too") {
  Grid g = sphere_grid({33, 29, 41}, glm::vec3(0.05f), glm::dvec3(0.0), 0.6);
  const std::size_t plane = 33 * 29;
  const std::size_t late = 30 * plane + 5 * 33 + 7, later = 35 * plane;
  const std::string inf_at_later = "element " + std::to_string(later) + " is inf";
  const std::string nan_at_late = "element " + std::to_string(late) + " is nan";
  g.values[later] = std::numeric_limits<float>::infinity();
  CHECK_THROWS_WITH_AS(gpu_mesh(g), doctest::Contains(inf_at_later.c_str()), InputError);
  g.values[late] = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_WITH_AS(gpu_mesh(g), doctest::Contains(nan_at_late.c_str()), InputError);
  // In a later slab too (the index counts from the grid's start, not the slab's).
  MarchingCubesGpuOptions options;
  options.max_binding_bytes = 26 * 1024;
  CHECK_THROWS_WITH_AS(gpu_mesh(g, 0.f, options), doctest::Contains(nan_at_late.c_str()), InputError);
  g.values[0] = -std::numeric_limits<float>::infinity();
  CHECK_THROWS_WITH_AS(gpu_mesh(g), doctest::Contains("element 0 is -inf"), InputError);

  auto& ctx = test::context();
  const std::vector<float> v(27, 1.f);
  CHECK_THROWS_AS(marching_cubes_gpu(ctx, v, {3, -3, 3}, glm::vec3(0.f), glm::vec3(1.f)), InputError);
  CHECK_THROWS_AS(marching_cubes_gpu(ctx, v, {3, 3, 3}, glm::vec3(0.f), glm::vec3(1.f, 0.f, 1.f)), InputError);
  CHECK_THROWS_AS(marching_cubes_gpu(ctx, v, {3, 3, 3}, glm::vec3(0.f), glm::vec3(1.f, -1.f, 1.f)), InputError);
  CHECK_THROWS_AS(marching_cubes_gpu(ctx, v, {3, 3, 3}, glm::vec3(std::nanf("")), glm::vec3(1.f)), InputError);
  CHECK_THROWS_AS(marching_cubes_gpu(ctx, v, {3, 3, 3}, glm::vec3(0.f), glm::vec3(1.f), std::nanf("")), InputError);
  CHECK_THROWS_AS(marching_cubes_gpu(ctx, v, {3, 3, 4}, glm::vec3(0.f), glm::vec3(1.f)), InputError);  // 27 != 36
}
