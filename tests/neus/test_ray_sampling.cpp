// Ray selection for the NeuS surface stage (engine/neus/ray_sampling.hpp): an analytic sphere of
// radius 0.5 at (3, -2, 1) seen by a ring of 8 cameras, masks computed analytically (the ray through
// the pixel centre hits the sphere), a hand-built hull (cells touching the sphere, dilated by one
// cell). Hard cases: a camera inside the unit sphere, an all-zero mask, an empty class.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "engine/core/error.hpp"
#include "engine/io/scene.hpp"
#include "engine/neus/ray_sampling.hpp"
#include "engine/neus/visual_hull.hpp"
#include "tests/support/scene_fixtures.hpp"

using namespace nf;
using neus::RayClass;

namespace {

constexpr double kPi = 3.14159265358979323846;
const glm::dvec3 kCentre(3.0, -2.0, 1.0);
constexpr double kRadius = 0.5;


// Ray (origin, unit direction) vs sphere: the [t0, t1] interval, false on a miss or behind.
bool hit_sphere(glm::dvec3 o, glm::dvec3 d, glm::dvec3 c, double r, double& t0, double& t1) {
  const glm::dvec3 oc = o - c;
  const double b = glm::dot(oc, d), disc = b * b - (glm::dot(oc, oc) - r * r);
  if (disc < 0) return false;
  t0 = -b - std::sqrt(disc), t1 = -b + std::sqrt(disc);
  return t1 > 0;
}

std::vector<std::uint8_t> sphere_mask(const io::Camera& c) {
  std::vector<std::uint8_t> m(std::size_t(c.width) * c.height, 0);
  const glm::dvec3 o(c.camera_to_world[3]);
  for (std::uint32_t y = 0; y < c.height; ++y)
    for (std::uint32_t x = 0; x < c.width; ++x) {
      const glm::dvec3 dc((x + 0.5 - c.cx) / c.fx, -(y + 0.5 - c.cy) / c.fy, -1.0);
      const glm::dvec3 d = glm::normalize(glm::dmat3(c.camera_to_world) * dc);
      double t0, t1;
      m[std::size_t(y) * c.width + x] = hit_sphere(o, d, kCentre, kRadius, t0, t1) ? 1 : 0;
    }
  return m;
}

struct Fixture {
  io::Scene scene;
  std::vector<std::vector<std::uint8_t>> masks;
  neus::OccupancyGrid hull;
  neus::Normalisation norm;
};

// The 8-camera ring (distance 3, elevations +-25 deg, 96 x 80 pixels) and a hull of `res`^3 cells.
Fixture make_fixture(int res = 48) {
  Fixture f;
  for (int i = 0; i < 8; ++i) {
    const double az = 2 * kPi * i / 8, el = (i % 2 ? 25.0 : -25.0) * kPi / 180.0;
    const glm::dvec3 eye = kCentre + 3.0 * glm::dvec3(std::cos(el) * std::cos(az), std::sin(el), std::cos(el) * std::sin(az));
    f.scene.cameras.push_back(test::pinhole_camera("c" + std::to_string(i), test::look_at(eye, kCentre), 96, 80, 40.0));
    f.masks.push_back(sphere_mask(f.scene.cameras.back()));
  }
  neus::OccupancyGrid g;
  g.lo = kCentre - 0.75, g.hi = kCentre + 0.75, g.dims = glm::ivec3(res);
  g.occupied.assign(g.cell_count(), 0);
  for (int k = 0; k < res; ++k)
    for (int j = 0; j < res; ++j)
      for (int i = 0; i < res; ++i) {
        const glm::dvec3 lo = g.cell_lo(i, j, k), hi = lo + g.cell_size();
        const glm::dvec3 q = glm::clamp(kCentre, lo, hi);
        g.occupied[g.index(i, j, k)] = glm::length(q - kCentre) <= kRadius;
      }
  f.hull = neus::dilate(g, 1);
  f.norm = neus::normalise_to_unit_sphere(f.hull);
  return f;
}

int class_count(const std::vector<neus::Ray>& rays, RayClass c) {
  int n = 0;
  for (const neus::Ray& r : rays) n += r.cls == std::uint8_t(c);
  return n;
}

}  // namespace

TEST_CASE("ray pool: class counts match the masks (brute-force band)") {
  const Fixture f = make_fixture(16);
  const int band = 4;
  const neus::RayPool pool = neus::build_ray_pool(f.scene, f.masks, {band});
  REQUIRE(pool.cameras.size() == 8);
  for (std::size_t i = 0; i < 8; ++i) {
    const io::Camera& c = f.scene.cameras[i];
    const int w = int(c.width), h = int(c.height);
    std::size_t inside = 0, in_band = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (f.masks[i][std::size_t(y * w + x)]) {
          ++inside;
          continue;
        }
        bool near_mask = false;
        for (int dy = -band; dy <= band && !near_mask; ++dy)
          for (int dx = -band; dx <= band && !near_mask; ++dx) {
            const int xx = x + dx, yy = y + dy;
            near_mask = xx >= 0 && yy >= 0 && xx < w && yy < h && f.masks[i][std::size_t(yy * w + xx)];
          }
        in_band += near_mask;
      }
    CHECK(inside > 100);
    CHECK(in_band > 0);
    CHECK(pool.count(i, RayClass::inside) == inside);
    CHECK(pool.count(i, RayClass::band) == in_band);
    CHECK(pool.count(i, RayClass::background) == std::size_t(w * h) - inside - in_band);
    for (std::uint32_t p : pool.cameras[i].pixels[0]) CHECK(f.masks[i][p] == 1);
  }
  CHECK_THROWS_AS(neus::build_ray_pool(f.scene, {f.masks[0]}), InputError);
  auto bad = f.masks;
  bad[3].pop_back();
  CHECK_THROWS_AS(neus::build_ray_pool(f.scene, bad), InputError);
}

TEST_CASE("sample_rays: shares, unit directions, inside rays hit the sphere, hull intervals contain the hit") {
  const Fixture f = make_fixture();
  const neus::RayPool pool = neus::build_ray_pool(f.scene, f.masks);
  const std::uint32_t count = 20000;
  for (const bool with_hull : {false, true}) {
    CAPTURE(with_hull);
    const neus::OccupancyGrid* hull = with_hull ? &f.hull : nullptr;
    const std::vector<neus::Ray> rays = neus::sample_rays(pool, f.scene, f.norm, hull, count, 7);
    REQUIRE(rays.size() == count);
    // Shares: 0.8 / 0.15 / 0.05 (within 4 sigma of a multinomial; the counts are in fact fixed).
    const double shares[3] = {0.80, 0.15, 0.05};
    for (int c = 0; c < 3; ++c) {
      const double got = double(class_count(rays, RayClass(c))) / count;
      CHECK(std::abs(got - shares[c]) <= 4 * std::sqrt(shares[c] * (1 - shares[c]) / count));
    }
    const glm::dvec3 centre_u = f.norm.to_unit(kCentre);
    const double radius_u = kRadius * f.norm.scale;
    for (const neus::Ray& r : rays) {
      CHECK(std::abs(glm::length(r.direction) - 1.f) < 1e-5f);
      CHECK((std::isfinite(r.near) && std::isfinite(r.far)));
      if (r.cls != std::uint8_t(RayClass::background)) REQUIRE(r.hit());
      if (!r.hit()) continue;
      CHECK(r.near >= 1e-3f);
      // [near, far] lies in the unit sphere.
      CHECK(glm::length(glm::dvec3(r.origin) + double(r.far) * glm::dvec3(r.direction)) <= 1.0 + 1e-4);
      if (with_hull) {  // tightened: both ends lie in the hull's box
        const glm::dvec3 lo = f.norm.to_unit(f.hull.lo) - 1e-4, hi = f.norm.to_unit(f.hull.hi) + 1e-4;
        for (const float t : {r.near, r.far}) {
          const glm::dvec3 p = glm::dvec3(r.origin) + double(t) * glm::dvec3(r.direction);
          CHECK((glm::all(glm::greaterThanEqual(p, lo)) && glm::all(glm::lessThanEqual(p, hi))));
        }
      }
      if (r.cls != std::uint8_t(RayClass::inside)) continue;
      // In world space the (jittered) ray hits the sphere grown by a pixel's footprint at depth 3.5.
      const io::Camera& cam = f.scene.cameras[r.camera];
      const glm::dvec3 ow = f.norm.to_world(glm::dvec3(r.origin));
      double w0, w1;
      CHECK(hit_sphere(ow, glm::dvec3(r.direction), kCentre, kRadius + 3.5 * 0.75 / cam.fx, w0, w1));
      // In unit coordinates the hit interval of the sphere (when hit) lies inside [near, far].
      double t0, t1;
      if (hit_sphere(glm::dvec3(r.origin), glm::dvec3(r.direction), centre_u, radius_u, t0, t1)) {
        CHECK(double(r.near) <= t0 + 1e-4);
        CHECK(double(r.far) >= t1 - 1e-4);
      }
    }
  }
}

TEST_CASE("sample_rays: without jitter every inside ray hits the sphere exactly") {
  const Fixture f = make_fixture();
  const neus::RayPool pool = neus::build_ray_pool(f.scene, f.masks);
  neus::RaySampleOptions opt;
  opt.jitter = false;
  const std::vector<neus::Ray> rays = neus::sample_rays(pool, f.scene, f.norm, &f.hull, 5000, 3, opt);
  int inside = 0;
  for (const neus::Ray& r : rays) {
    if (r.cls != std::uint8_t(RayClass::inside)) continue;
    ++inside;
    double t0, t1;
    CHECK(hit_sphere(f.norm.to_world(glm::dvec3(r.origin)), glm::dvec3(r.direction), kCentre, kRadius + 1e-6, t0, t1));
  }
  CHECK(inside == 4000);
}

TEST_CASE("sample_rays: the same seed gives the same rays, another seed others") {
  const Fixture f = make_fixture(24);
  const neus::RayPool pool = neus::build_ray_pool(f.scene, f.masks);
  const auto a = neus::sample_rays(pool, f.scene, f.norm, &f.hull, 3000, 11);
  const auto b = neus::sample_rays(pool, f.scene, f.norm, &f.hull, 3000, 11);
  const auto c = neus::sample_rays(pool, f.scene, f.norm, &f.hull, 3000, 12);
  REQUIRE(a.size() == b.size());
  int same_as_c = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(a[i].origin == b[i].origin);
    CHECK(a[i].direction == b[i].direction);
    CHECK(a[i].near == b[i].near);
    CHECK(a[i].far == b[i].far);
    CHECK(a[i].pixel == b[i].pixel);
    CHECK(a[i].camera == b[i].camera);
    CHECK(a[i].cls == b[i].cls);
    same_as_c += a[i].direction == c[i].direction;
  }
  CHECK(same_as_c < 30);
}

TEST_CASE("hard case: a camera inside the unit sphere gets near = epsilon and finite rays") {
  Fixture f = make_fixture(32);
  // Inside the object, looking along +x; no mask: all its pixels are "inside".
  f.scene.cameras.push_back(test::pinhole_camera("inner", test::look_at(kCentre + glm::dvec3(-0.1, 0.05, 0), kCentre + glm::dvec3(1, 0, 0)), 32, 24, 90.0));
  f.masks.emplace_back();
  const neus::RayPool pool = neus::build_ray_pool(f.scene, f.masks);
  CHECK(pool.count(8, RayClass::inside) == 32 * 24);
  CHECK(pool.count(8, RayClass::band) == 0);
  REQUIRE(glm::length(f.norm.to_unit(glm::dvec3(f.scene.cameras[8].camera_to_world[3]))) < 1.0);
  neus::RaySampleOptions opt;
  opt.near_epsilon = 2e-3f;
  for (const bool with_hull : {false, true}) {
    const auto rays = neus::sample_rays(pool, f.scene, f.norm, with_hull ? &f.hull : nullptr, 20000, 5, opt);
    int inner = 0;
    for (const neus::Ray& r : rays) {
      if (r.camera != 8) continue;
      ++inner;
      REQUIRE(r.hit());
      CHECK(r.near == opt.near_epsilon);
      CHECK(std::isfinite(r.far));
      CHECK(r.far <= 2.0f);
    }
    CHECK(inner > 100);
  }
}

TEST_CASE("hard case: an all-zero mask contributes background rays only; empty classes renormalise") {
  Fixture f = make_fixture(24);
  std::fill(f.masks[2].begin(), f.masks[2].end(), std::uint8_t(0));
  const neus::RayPool pool = neus::build_ray_pool(f.scene, f.masks);
  CHECK(pool.count(2, RayClass::inside) == 0);
  CHECK(pool.count(2, RayClass::band) == 0);
  CHECK(pool.count(2, RayClass::background) == 96 * 80);
  const auto rays = neus::sample_rays(pool, f.scene, f.norm, &f.hull, 20000, 9);
  int from_2 = 0;
  for (const neus::Ray& r : rays)
    if (r.camera == 2) {
      ++from_2;
      CHECK(r.cls == std::uint8_t(RayClass::background));
    }
  CHECK(from_2 > 0);
  // Missed rays are background only; some background rays miss the hull.
  int missed = 0;
  for (const neus::Ray& r : rays) {
    if (!r.hit()) {
      ++missed;
      CHECK(r.cls == std::uint8_t(RayClass::background));
    }
  }
  CHECK(missed > 0);

  // No band (band_px = 0): inside and background shares renormalise to 0.8 / 0.85 and 0.05 / 0.85.
  const neus::RayPool no_band = neus::build_ray_pool(f.scene, f.masks, {0});
  CHECK(no_band.count(RayClass::band) == 0);
  const auto r2 = neus::sample_rays(no_band, f.scene, f.norm, nullptr, 1700, 1);
  CHECK(class_count(r2, RayClass::inside) == 1600);
  CHECK(class_count(r2, RayClass::band) == 0);
  CHECK(class_count(r2, RayClass::background) == 100);

  neus::RaySampleOptions zero;
  zero.inside_share = zero.band_share = zero.background_share = 0.f;
  CHECK_THROWS_AS(neus::sample_rays(pool, f.scene, f.norm, nullptr, 10, 1, zero), InputError);
}
