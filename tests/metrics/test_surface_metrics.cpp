// Surface metrics and the strand-tip chamfer on analytic meshes.
#include <doctest/doctest.h>

#include <cmath>

#include "engine/metrics/surface_metrics.hpp"

using namespace nf;
using namespace nf::metrics;

namespace {

// A UV sphere of radius r.
geometry::Mesh sphere(float r, int rings = 48, int segments = 96) {
  geometry::Mesh m;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j <= segments; ++j) {
      const double th = 3.14159265358979 * i / rings, ph = 2 * 3.14159265358979 * j / segments;
      m.positions.insert(m.positions.end(), {float(r * std::sin(th) * std::cos(ph)), float(r * std::cos(th)),
                                             float(r * std::sin(th) * std::sin(ph))});
    }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const std::uint32_t a = i * (segments + 1) + j, b = a + segments + 1;
      m.triangles.insert(m.triangles.end(), {a, b, a + 1, a + 1, b, b + 1});
    }
  return m;
}

}  // namespace

TEST_CASE("a mesh against itself: zero chamfer, perfect normals, F-score 100") {
  const geometry::Mesh s = sphere(1.f);
  const auto m = surface_metrics(s, s, 1.0, 1.0, 20000, 3);
  CHECK(m.chamfer_mean_mm == doctest::Approx(0).epsilon(1e-9));
  CHECK(m.normal_consistency == doctest::Approx(1.0));
  CHECK(m.fscore == doctest::Approx(100));
}

TEST_CASE("concentric spheres 1 cm apart are 10 mm apart, in both directions") {
  const auto m = surface_metrics(sphere(11.f), sphere(10.f), 1.0, 5.0, 20000, 3);  // 1 unit = 1 cm
  CHECK(m.accuracy_mm == doctest::Approx(10).epsilon(0.05));
  CHECK(m.completeness_mm == doctest::Approx(10).epsilon(0.05));
  CHECK(m.chamfer_min_mm >= 9.0);
  CHECK(m.normal_consistency > 0.98);
  CHECK(m.fscore == doctest::Approx(0));  // nothing within 5 mm
  CHECK(surface_metrics(sphere(11.f), sphere(10.f), 1.0, 15.0, 20000, 3).fscore == doctest::Approx(100));
}

TEST_CASE("strand tips on the outer surface are close to it; tips short of it are not") {
  // Radial strands from a 10 cm sphere, 1 cm long, against an outer sphere of 11 cm.
  std::vector<float> on, short_of;
  const geometry::Mesh body = sphere(10.f, 24, 48);
  for (std::uint64_t v = 0; v < body.vertex_count(); ++v) {
    const float* p = &body.positions[3 * v];
    for (int k = 0; k < 5; ++k) {
      const float t = 1.f + 0.1f * float(k) / 4.f, t2 = 1.f + 0.05f * float(k) / 4.f;
      on.insert(on.end(), {p[0] * t, p[1] * t, p[2] * t});
      short_of.insert(short_of.end(), {p[0] * t2, p[1] * t2, p[2] * t2});
    }
  }
  const auto n = std::uint32_t(body.vertex_count());
  const auto outer = sphere(11.f, 24, 48);
  const auto good = tip_chamfer(sample_strands(io::StrandSet::uniform(n, 5, on), n, 5, 1), outer, 1.0, 20000, 2);
  const auto bad = tip_chamfer(sample_strands(io::StrandSet::uniform(n, 5, short_of), n, 5, 1), outer, 1.0, 20000, 2);
  CHECK(good.tips_to_surface_mm < 2.0);
  CHECK(bad.tips_to_surface_mm == doctest::Approx(5.0).epsilon(0.2));  // tips 0.5 cm short
  CHECK(bad.two_way_mm > good.two_way_mm);
}
