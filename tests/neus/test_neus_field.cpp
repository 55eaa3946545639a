// The NeuS field (engine/neus/neus_field.hpp): geometric initialisation, the inference path
// against the training path, and the finite-difference normals.
#include <doctest/doctest.h>

#include <cmath>

#include "engine/neus/neus_field.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;

namespace {

std::vector<glm::vec3> probe_points() {
  std::vector<glm::vec3> p;
  for (int i = 0; i < 200; ++i) {
    const float t = float(i) * 0.61803f;
    const float r = 0.1f + 0.8f * float(i % 17) / 16.f;
    p.push_back(r * glm::normalize(glm::vec3(std::sin(3.1f * t), std::cos(1.7f * t + 0.3f), std::sin(0.7f * t + 1.f))));
  }
  return p;
}

}  // namespace

TEST_CASE("geometric initialisation: the field starts as a sphere, in inference and training paths alike") {
  for (const neus::FieldEncoding encoding : {neus::FieldEncoding::HashGrid, neus::FieldEncoding::Frequency}) {
    neus::NeusFieldConfig config;
    config.encoding = encoding;
    config.hash = {8, 2, 14, 16, 256};
    neus::NeusField field(test::context(), config, 3);
    const std::vector<glm::vec3> points = probe_points();
    const std::vector<float> sdf = field.sdf_at(points);
    std::vector<glm::vec3> dirs(points.size(), glm::vec3(0.f, 0.f, -1.f));
    const float h = 1e-3f;
    const neus::NeusField::Shading shading = field.shade(points, dirs, h);
    int far = 0, agree = 0;
    double error = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      CAPTURE(i);
      const float r = glm::length(points[i]);
      CHECK(std::isfinite(sdf[i]));
      // SAL initialisation of one 64-wide layer: a rough sphere of radius 0.5 (inside negative,
      // outside positive away from the shell, gradients pointing outwards, roughly unit length).
      error += std::fabs(sdf[i] - (r - 0.5f));
      if (std::fabs(r - 0.5f) > 0.2f) ++far, agree += (sdf[i] < 0.f) == (r < 0.5f);
      CHECK(std::fabs(sdf[i] - shading.sdf[i]) < 1e-4f);  // inference = mean of the tetrahedron, O(h^2)
      const glm::vec3 g = shading.gradient[i];
      CHECK(glm::dot(glm::normalize(g), points[i] / r) > 0.7f);
      CHECK((glm::length(g) > 0.4f && glm::length(g) < 1.6f));
      for (int c = 0; c < 3; ++c) CHECK((shading.rgb[i][c] > 0.f && shading.rgb[i][c] < 1.f));
    }
    MESSAGE("sphere init: mean |sdf - (r - 0.5)| = ", error / points.size(), ", sign right at ", agree, " of ", far,
            " points away from the shell");
    CHECK(error / double(points.size()) < 0.1);
    CHECK(agree >= 0.95 * far);
  }
}
