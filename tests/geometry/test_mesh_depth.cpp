// Body depth map (the strand splatter's occluder): GPU against the CPU reference, analytic depths,
// the near plane, big triangles, image sizes, empty meshes, bad input.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/core/error.hpp"
#include "engine/geometry/marching_cubes.hpp"
#include "engine/geometry/mesh_depth.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::geometry;

namespace {

struct TriMesh {
  std::vector<float> positions;
  std::vector<std::uint32_t> triangles;
};

// A closed marching-cubes sphere of radius r at `centre` with about (2r / voxel)^3 samples.
TriMesh mc_sphere(glm::vec3 centre, float r, float voxel) {
  const int n = int(std::ceil(2 * r / voxel)) + 5;
  const glm::vec3 origin = centre - glm::vec3(0.5f * float(n - 1) * voxel);
  std::vector<float> values(std::size_t(n) * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        values[(std::size_t(k) * n + j) * n + i] = glm::length(origin + voxel * glm::vec3(i, j, k) - centre) - r;
  const geometry::Mesh m = geometry::marching_cubes(values.data(), {n, n, n}, origin, glm::vec3(voxel));
  return {m.positions, m.triangles};
}

DepthCamera look_at(glm::vec3 eye, glm::vec3 target, std::uint32_t w, std::uint32_t h, float f) {
  DepthCamera c;
  c.world_to_camera = glm::lookAt(eye, target, glm::vec3(0, 1, 0));
  c.fx = c.fy = f;
  c.cx = 0.5f * float(w), c.cy = 0.5f * float(h);
  c.width = w, c.height = h;
  c.near = 0.01f;
  return c;
}

// GPU and reference agree: same coverage, depths within 1e-5 relative. Returns the covered count.
std::size_t require_match(const std::vector<float>& gpu, const std::vector<float>& ref) {
  REQUIRE(gpu.size() == ref.size());
  std::size_t covered = 0, mismatched = 0;
  double worst = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    if (std::isinf(ref[i]) || std::isinf(gpu[i])) {
      if (std::isinf(ref[i]) != std::isinf(gpu[i])) ++mismatched;
      continue;
    }
    ++covered;
    worst = std::max(worst, std::abs(double(gpu[i]) - ref[i]) / std::abs(double(ref[i])));
  }
  CHECK(mismatched == 0);
  CHECK(worst <= 1e-5);
  return covered;
}

std::size_t count_finite(const std::vector<float>& d) {
  std::size_t n = 0;
  for (float x : d) n += std::isfinite(x);
  return n;
}

// Camera-space ray of a pixel centre (depth 1).
glm::dvec3 pixel_ray(const DepthCamera& c, double x, double y) {
  return {(x + 0.5 - c.cx) / c.fx, -(y + 0.5 - c.cy) / c.fy, -1.0};
}

}  // namespace

TEST_CASE("a marching-cubes sphere: GPU equals the reference, centre depth is distance - radius, no cracks") {
  auto& ctx = test::context();
  const glm::vec3 centre(0.1f, -0.2f, 0.3f);
  const float r = 0.5f;
  const TriMesh s = mc_sphere(centre, r, 0.02f);
  REQUIRE(s.triangles.size() / 3 > 5000);
  const glm::vec3 eye = centre + glm::vec3(0.3f, 0.4f, 2.0f);
  const float dist = glm::length(eye - centre);
  const DepthCamera cam = look_at(eye, centre, 160, 120, 150.0f);
  const auto gpu = mesh_depth(ctx, cam, s.positions, s.triangles);
  const auto ref = mesh_depth_ref(cam, s.positions, s.triangles);
  CHECK(require_match(gpu, ref) > 1000);
  // The image centre (80, 60) is a pixel corner: average the four pixels around it.
  double centre_depth = 0;
  for (int y = 59; y <= 60; ++y)
    for (int x = 79; x <= 80; ++x) centre_depth += 0.25 * gpu[std::size_t(y) * 160 + x];
  CHECK(centre_depth == doctest::Approx(dist - r).epsilon(1e-3));
  // Every pixel: analytic ray-sphere depth (the MC surface lies within ~voxel^2/r of the sphere),
  // and every ray that passes well inside the silhouette is covered (no cracks).
  const glm::dmat4 w2c(cam.world_to_camera);
  const glm::dvec3 c_cam(w2c * glm::dvec4(glm::dvec3(centre), 1.0));
  std::size_t inside = 0;
  for (std::uint32_t y = 0; y < cam.height; ++y)
    for (std::uint32_t x = 0; x < cam.width; ++x) {
      const glm::dvec3 d = pixel_ray(cam, x, y);
      const double a = glm::dot(d, d), b = glm::dot(d, c_cam), cc = glm::dot(c_cam, c_cam) - double(r) * r;
      const double disc = b * b - a * cc;
      const float got = gpu[std::size_t(y) * cam.width + x];
      const double miss = std::sqrt(std::max(0.0, cc + double(r) * r - b * b / a));  // ray-centre distance
      if (miss < r - 0.03) {
        ++inside;
        REQUIRE(std::isfinite(got));
        CHECK(got == doctest::Approx((b - std::sqrt(disc)) / a).epsilon(2e-3));
      } else if (miss > r + 0.03) {
        CHECK(std::isinf(got));
      }
    }
  CHECK(inside > 1000);
}

TEST_CASE("random triangles, some behind the camera or across the near plane: GPU equals the reference") {
  auto& ctx = test::context();
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  TriMesh m;
  for (int f = 0; f < 600; ++f) {
    // Camera at the origin looking down -z (identity pose); triangles around z in [-3, 0.5].
    const glm::vec3 c(2 * u(rng), 2 * u(rng), -1.25f + 1.75f * u(rng));
    const float size = f % 10 == 0 ? 3.0f : 0.3f;
    for (int k = 0; k < 3; ++k) {
      m.positions.push_back(c.x + size * u(rng));
      m.positions.push_back(c.y + size * u(rng));
      m.positions.push_back(c.z + size * u(rng));
      m.triangles.push_back(std::uint32_t(3 * f + k));
    }
  }
  for (const std::uint32_t tile : {8u, 1u, 5u}) {
    DepthCamera cam;
    cam.width = 200, cam.height = 150, cam.fx = cam.fy = 120, cam.cx = 100.3f, cam.cy = 74.8f;
    cam.near = 0.05f;
    MeshDepthOptions options;
    options.tile = tile;
    const auto gpu = mesh_depth(ctx, cam, m.positions, m.triangles, options);
    const auto ref = mesh_depth_ref(cam, m.positions, m.triangles);
    CHECK(require_match(gpu, ref) > 5000);
    for (float d : gpu) CHECK((std::isinf(d) || d >= cam.near));
  }
}

TEST_CASE("a plane filling the view (big triangles): its depth everywhere, tilted plane analytic") {
  auto& ctx = test::context();
  for (const auto& [w, h] : {std::pair{1u, 1u}, std::pair{1920u, 1080u}, std::pair{37u, 5u}}) {
    DepthCamera cam;
    cam.width = w, cam.height = h, cam.fx = cam.fy = 0.8f * float(std::max(w, h)), cam.cx = 0.5f * float(w),
    cam.cy = 0.5f * float(h);
    // Fronto-parallel at depth 3, two triangles far larger than the frustum.
    const std::vector<float> flat = {-50, -50, -3, 50, -50, -3, 50, 50, -3, -50, 50, -3};
    const std::vector<std::uint32_t> quad = {0, 1, 2, 0, 2, 3};
    const auto d = mesh_depth(ctx, cam, flat, quad);
    REQUIRE(d.size() == std::size_t(w) * h);
    // Exact on lavapipe; GPUs contract the interpolation's multiply-adds, so allow a few ulp.
    CHECK(std::all_of(d.begin(), d.end(), [](float x) { return std::fabs(x - 3.0f) <= 4 * 2.4e-7f * 3.0f; }));
    // Tilted: the plane z = -3 + 0.5 x.
    std::vector<float> tilted = flat;
    for (int v = 0; v < 4; ++v) tilted[3 * v + 2] = -3.0f + 0.5f * tilted[3 * v];
    const auto t = mesh_depth(ctx, cam, tilted, quad);
    require_match(t, mesh_depth_ref(cam, tilted, quad));
    for (std::uint32_t y = 0; y < h; y += std::max(1u, h / 17))
      for (std::uint32_t x = 0; x < w; x += std::max(1u, w / 23)) {
        const glm::dvec3 r = pixel_ray(cam, x, y);
        const double depth = 3.0 / (1.0 + 0.5 * r.x);  // -t = -3 + 0.5 t r.x
        CHECK(t[std::size_t(y) * w + x] == doctest::Approx(depth).epsilon(1e-5));
      }
  }
}

TEST_CASE("a 1920x1080 sphere view and a 1x1 view agree with the reference") {
  auto& ctx = test::context();
  const TriMesh s = mc_sphere(glm::vec3(0), 0.4f, 0.03f);
  for (const auto& [w, h] : {std::pair{1920u, 1080u}, std::pair{1u, 1u}}) {
    const DepthCamera cam = look_at(glm::vec3(0.2f, 0.1f, 1.5f), glm::vec3(0), w, h, 1.2f * float(w));
    const auto gpu = mesh_depth(ctx, cam, s.positions, s.triangles);
    const auto ref = mesh_depth_ref(cam, s.positions, s.triangles);
    CHECK(require_match(gpu, ref) == (w == 1 ? 1u : count_finite(ref)));
  }
}

TEST_CASE("triangles behind the camera do not appear; one crossing the near plane is cut at the plane") {
  auto& ctx = test::context();
  DepthCamera cam;
  cam.width = 64, cam.height = 48, cam.fx = cam.fy = 40, cam.cx = 32, cam.cy = 24, cam.near = 0.1f;
  // Behind the camera (z > 0), a big one and a small one; and one between the camera and the near plane.
  const std::vector<float> behind = {-5, -5, 2, 5, -5, 2, 0, 5, 2, -0.1f, -0.1f, 0.5f, 0.1f, -0.1f, 0.5f, 0, 0.1f, 0.5f,
                                     -0.1f, -0.1f, -0.05f, 0.1f, -0.1f, -0.05f, 0, 0.1f, -0.05f};
  const std::vector<std::uint32_t> three = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  const auto d = mesh_depth(ctx, cam, behind, three);
  CHECK(count_finite(d) == 0);
  CHECK(count_finite(mesh_depth_ref(cam, behind, three)) == 0);

  // A floor y = -1 running from far in front of the camera to behind it: it crosses the near
  // plane and the camera plane. Below the horizon the depth is -1 / d_y; above it nothing.
  const std::vector<float> floor = {-100, -1, -100, 100, -1, -100, 0, -1, 100};
  const std::vector<std::uint32_t> one = {0, 1, 2};
  const auto g = mesh_depth(ctx, cam, floor, one);
  require_match(g, mesh_depth_ref(cam, floor, one));
  std::size_t below = 0;
  for (std::uint32_t y = 0; y < cam.height; ++y)
    for (std::uint32_t x = 0; x < cam.width; ++x) {
      const glm::dvec3 r = pixel_ray(cam, x, y);
      const float got = g[std::size_t(y) * cam.width + x];
      if (r.y < 0) {
        const double t = -1.0 / r.y;
        const glm::dvec3 p = t * r;  // inside the triangle: z >= -100 and |x| <= (100 - z) / 2
        if (p.z >= -95 && std::abs(p.x) <= (100 - p.z) / 2 - 1) {
          ++below;
          CHECK(got == doctest::Approx(t).epsilon(1e-5));
        }
      } else {
        CHECK(std::isinf(got));
      }
    }
  CHECK(below > 500);

  // The near plane itself: a wall at depth 0.05 < near is invisible; at 0.15 it is seen.
  const std::vector<float> wall_near = {-5, -5, -0.05f, 5, -5, -0.05f, 0, 5, -0.05f};
  CHECK(count_finite(mesh_depth(ctx, cam, wall_near, one)) == 0);
  const std::vector<float> wall_far = {-5, -5, -0.15f, 5, -5, -0.15f, 0, 5, -0.15f};
  const auto wf = mesh_depth(ctx, cam, wall_far, one);
  CHECK(count_finite(wf) > 1000);
  require_match(wf, mesh_depth_ref(cam, wall_far, one));
  // A sloped triangle through the near plane: only the part beyond near is drawn.
  const std::vector<float> slope = {-1, -0.5f, 0.2f, 1, -0.5f, 0.2f, 0, 0.5f, -1.0f};
  const auto sl = mesh_depth(ctx, cam, slope, one);
  require_match(sl, mesh_depth_ref(cam, slope, one));
  CHECK(count_finite(sl) > 100);
  for (float x : sl) CHECK((std::isinf(x) || x >= cam.near));
}

TEST_CASE("an empty mesh gives an empty depth map; bad input is rejected with the field named") {
  auto& ctx = test::context();
  DepthCamera cam;
  cam.width = 33, cam.height = 17, cam.fx = cam.fy = 20, cam.cx = 16, cam.cy = 8;
  const auto d = mesh_depth(ctx, cam, {}, {});
  REQUIRE(d.size() == 33u * 17u);
  CHECK(count_finite(d) == 0);
  const std::vector<float> pts = {0, 0, -1, 1, 0, -1, 0, 1, -1};
  CHECK(count_finite(mesh_depth(ctx, cam, pts, {})) == 0);

  const std::vector<std::uint32_t> bad = {0, 1, 3};
  CHECK_THROWS_WITH_AS(mesh_depth(ctx, cam, pts, bad), doctest::Contains("triangle 0 uses vertex 3"), InputError);
  std::vector<float> nan_pts = pts;
  nan_pts[4] = std::nanf("");
  CHECK_THROWS_WITH_AS(mesh_depth(ctx, cam, nan_pts, std::vector<std::uint32_t>{0, 1, 2}),
                       doctest::Contains("mesh positions"), InputError);
  DepthCamera zero = cam;
  zero.width = 0;
  CHECK_THROWS_WITH_AS(mesh_depth(ctx, zero, pts, {}), doctest::Contains("camera size"), InputError);
  DepthCamera no_near = cam;
  no_near.near = 0;
  CHECK_THROWS_WITH_AS(mesh_depth_ref(no_near, pts, {}), doctest::Contains("near"), InputError);
  DepthCamera no_f = cam;
  no_f.fy = -1;
  CHECK_THROWS_WITH_AS(mesh_depth(ctx, no_f, pts, {}), doctest::Contains("focal"), InputError);
}

TEST_CASE("timing: a 512x512 depth map of an ~80k-triangle mesh") {
  auto& ctx = test::context();
  const TriMesh s = mc_sphere(glm::vec3(0), 0.5f, 0.011f);
  const std::size_t faces = s.triangles.size() / 3;
  CHECK(faces > 70000);
  const DepthCamera cam = look_at(glm::vec3(0.3f, 0.5f, 1.6f), glm::vec3(0), 512, 512, 450.0f);
  gpu::Buffer<float> positions(ctx, s.positions, "positions");
  gpu::Buffer<std::uint32_t> triangles(ctx, s.triangles, "triangles");
  gpu::Buffer<float> depth(ctx, 512 * 512, "depth");
  gpu::Stream stream(ctx);
  double best = 1e30, best_gpu = 1e30;
  for (int run = 0; run < 4; ++run) {
    const auto t0 = std::chrono::steady_clock::now();
    stream.begin_pass("mesh_depth");
    mesh_depth(stream, cam, positions, s.positions.size() / 3, triangles, faces, depth);
    stream.end_pass();
    stream.submit_and_wait();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    for (const auto& p : stream.last_pass_times()) best_gpu = std::min(best_gpu, p.milliseconds);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const auto ref = mesh_depth_ref(cam, s.positions, s.triangles);
  const double cpu = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto got = depth.download();
  require_match(got, ref);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < got.size(); ++i) differ += got[i] != ref[i];
  MESSAGE("body depth 512x512, " << faces << " triangles: " << best * 1e3 << " ms wall (GPU pass " << best_gpu
                                 << " ms) on " << ctx.info().name << "; CPU reference " << cpu * 1e3 << " ms; "
                                 << differ << " pixels differ in any bit");
}
