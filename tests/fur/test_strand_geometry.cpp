// The strand geometry map (engine/fur/strand_geometry.*): points of the right length in the right
// frame, the decoder at zero, the lengths of the hard cases, refusals. Its gradients are in the
// gradcheck catalog (test_gradcheck).
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include <glm/glm.hpp>

#include "engine/core/error.hpp"
#include "engine/fur/strand_geometry.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::fur;

namespace {

// One strand's frame: root, length, T, B, N.
std::vector<float> frame(glm::vec3 root, float length, glm::vec3 t, glm::vec3 b, glm::vec3 n) {
  return {root.x, root.y, root.z, length, t.x, t.y, t.z, b.x, b.y, b.z, n.x, n.y, n.z};
}

float arc_length(const std::vector<float>& points, std::uint32_t strand, std::uint32_t count) {
  float sum = 0;
  for (std::uint32_t k = 1; k < count; ++k) {
    const std::size_t a = (std::size_t(strand) * count + k - 1) * 3, b = a + 3;
    sum += std::sqrt((points[b] - points[a]) * (points[b] - points[a]) + (points[b + 1] - points[a + 1]) * (points[b + 1] - points[a + 1]) +
                     (points[b + 2] - points[a + 2]) * (points[b + 2] - points[a + 2]));
  }
  return sum;
}

}  // namespace

TEST_CASE("strand geometry: root first, arc length equal to the fur length, the frame's axes, GPU as the reference") {
  const StrandGeometryShape shape{3, 99, 300};
  std::vector<float> rows(std::size_t(shape.strands) * shape.row_stride, 0.f);
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(-0.005f, 0.005f);
  for (std::uint32_t j = 0; j < 99; ++j) {
    rows[3 * j + 2] = 1.f / 99;  // strand 0: straight along the normal
    for (int c = 0; c < 3; ++c) rows[300 + 3 * j + std::uint32_t(c)] = (c == 0 ? 0.01f : 0.f) + u(rng);  // strand 1: wiggly, along T
    rows[600 + 3 * j + 1] = 5.f;  // strand 2: along B, far too long (the length normalises it)
  }
  for (std::size_t c = 297; c < 300; ++c) rows[c] = 1e3f;  // padding: ignored
  std::vector<float> frames = frame({1, 2, 3}, 0.05f, {1, 0, 0}, {0, 1, 0}, {0, 0, 1});
  for (const auto& f : {frame({0, 0, 0}, 1e-4f, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}), frame({-5, 0, 0}, 1e3f, {0, 1, 0}, {0, 0, 1}, {1, 0, 0})})
    frames.insert(frames.end(), f.begin(), f.end());
  const std::vector<float> points = strand_points(test::context(), shape, rows, frames);
  std::vector<float> reference;
  strand_geometry_forward_ref(rows, frames, shape, reference);
  REQUIRE(points.size() == reference.size());
  for (std::size_t i = 0; i < points.size(); ++i) CHECK(points[i] == doctest::Approx(reference[i]).epsilon(1e-5).scale(1e-3));
  const float lengths[3]{0.05f, 1e-4f, 1e3f};
  for (std::uint32_t s = 0; s < 3; ++s) {
    CHECK(points[s * 300] == doctest::Approx(frames[s * 13]));  // the root
    CHECK(arc_length(points, s, 100) == doctest::Approx(lengths[s]).epsilon(1e-4));
  }
  // Strand 0 runs straight up its normal (+z) to the root + 0.05.
  CHECK(points[99 * 3 + 2] == doctest::Approx(3.05f).epsilon(1e-6));
  CHECK(points[99 * 3 + 0] == doctest::Approx(1.f));
  // Strand 2's local y is its bitangent, world z: the tip 1000 units along +z.
  CHECK(points[2 * 300 + 99 * 3 + 2] == doctest::Approx(1000.f).epsilon(1e-5));
}

TEST_CASE("strand geometry: a decoder at zero puts every point at the root, with finite gradients") {
  const StrandGeometryShape shape{2, 99, 297};
  const std::vector<float> rows(2 * 297, 0.f);
  std::vector<float> frames = frame({0.5f, 0, 0}, 0.05f, {1, 0, 0}, {0, 1, 0}, {0, 0, 1});
  const auto second = frame({0, 0.5f, 0}, 0.02f, {0, 1, 0}, {0, 0, 1}, {1, 0, 0});
  frames.insert(frames.end(), second.begin(), second.end());
  const std::vector<float> points = strand_points(test::context(), shape, rows, frames);
  for (std::uint32_t s = 0; s < 2; ++s)
    for (std::uint32_t k = 0; k < 100; ++k)
      for (int c = 0; c < 3; ++c) CHECK(points[(s * 100 + k) * 3 + std::uint32_t(c)] == frames[s * 13 + std::uint32_t(c)]);
  const std::vector<float> grad(points.size(), 1.f);
  const StrandGeometryGradients g = strand_points_backward(test::context(), shape, rows, frames, grad);
  for (float v : g.rows) CHECK(std::isfinite(v));
  for (float v : g.frames) CHECK(std::isfinite(v));
  CHECK(g.frames[0] == doctest::Approx(100.f));  // dL/droot.x: 100 points each with gradient 1
}

TEST_CASE("strand geometry refuses bad shapes and non-finite input, naming them") {
  const StrandGeometryShape shape{1, 99, 200};
  CHECK_THROWS_WITH_AS(strand_points(test::context(), shape, std::vector<float>(200), std::vector<float>(13)),
                       doctest::Contains("row stride 200"), InputError);
  const StrandGeometryShape good{1, 3, 9};
  CHECK_THROWS_WITH_AS(strand_points(test::context(), good, std::vector<float>(9), std::vector<float>(12)),
                       doctest::Contains("13 each"), InputError);
  std::vector<float> rows(9, 0.1f);
  rows[4] = std::nanf("");
  CHECK_THROWS_WITH_AS(strand_points(test::context(), good, rows, std::vector<float>(13, 0.f)), doctest::Contains("decoder rows"), InputError);
}
