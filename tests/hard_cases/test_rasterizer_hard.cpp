// Hard cases of the strand rasteriser (DESIGN §4, issue list): zero-length and edge-on segments,
// segments behind the camera or crossing the near plane, strands off screen, more than 10,000
// Gaussians in one tile, a 1x1 image, and an occluder in front of everything. Each must give finite
// images and gradients that agree with the CPU reference.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "engine/core/error.hpp"
#include "engine/splat/rasterizer.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::splat;

namespace {

RasterCamera front_camera(std::uint32_t w, std::uint32_t h, double focal = 60) {
  RasterCamera c;
  c.width = w, c.height = h, c.fx = c.fy = focal, c.cx = 0.5 * w, c.cy = 0.5 * h;
  c.world_to_camera[11] = -2;  // camera at z = 2 looking down -z
  c.near = 0.05, c.far = 10;
  return c;
}

RasterParams params(double width = 0.02) {
  RasterParams p;
  p.gaussian = {0.5, width};
  return p;
}

double max_abs(const std::vector<float>& v) {
  double m = 0;
  for (float x : v) {
    REQUIRE(std::isfinite(x));
    m = std::max(m, double(std::fabs(x)));
  }
  return m;
}

// GPU forward and adjoint against the float reference: relative to the largest magnitude.
void check_against_reference(gpu::Context& ctx, std::uint32_t strands, std::uint32_t L, const std::vector<float>& pts,
                             const RasterCamera& cam, const RasterParams& rp, const std::vector<float>& body = {},
                             double tolerance = 1e-4, double adjoint_tolerance = 1e-3) {
  const StrandShape shape{strands, L};
  const std::vector<float> conf(shape.segments(), 0.7f);
  const std::vector<float> image = rasterize(ctx, shape, pts, conf, cam, rp, body);
  std::vector<float> ref;
  rasterize_ref(pts, conf, strands, L, cam, rp, body, ref);
  REQUIRE(image.size() == ref.size());
  const double scale = std::max(1e-6, max_abs(ref));
  for (std::size_t i = 0; i < ref.size(); ++i) REQUIRE(std::fabs(image[i] - ref[i]) <= tolerance * scale + 1e-6);
  std::mt19937 rng(3);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<float> grad_image(image.size());
  for (float& x : grad_image) x = g(rng);
  const RasterGradients got = rasterize_backward(ctx, shape, pts, conf, cam, rp, body, grad_image);
  std::vector<float> want_points, want_conf;
  rasterize_adjoint_ref(pts, conf, strands, L, cam, rp, body, grad_image, want_points, want_conf);
  const double gscale = std::max(1e-6, max_abs(want_points));
  max_abs(got.points);
  for (std::size_t i = 0; i < want_points.size(); ++i)
    REQUIRE(std::fabs(got.points[i] - want_points[i]) <= adjoint_tolerance * gscale + 1e-6);
  const double cscale = max_abs(want_conf);
  for (std::size_t i = 0; i < want_conf.size(); ++i)
    REQUIRE(std::fabs(got.confidence[i] - want_conf[i]) <= adjoint_tolerance * cscale + 1e-6);
}

}  // namespace

TEST_CASE("rasteriser hard cases agree with the reference and stay finite") {
  gpu::Context& ctx = test::context();

  SUBCASE("zero-length segments and a strand collapsed to a point") {
    std::vector<float> pts = {0, 0, 0, 0, 0, 0, 0.1f, 0, 0, 0.1f, 0, 0,  // repeated points
                              0.2f, 0.1f, 0, 0.2f, 0.1f, 0, 0.2f, 0.1f, 0, 0.2f, 0.1f, 0};  // all one point
    check_against_reference(ctx, 2, 4, pts, front_camera(32, 32), params());
  }
  SUBCASE("segments seen exactly edge-on have no orientation, not a NaN") {
    std::vector<float> pts = {0, 0, 0.3f, 0, 0, 0.1f, 0, 0, -0.1f, 0, 0, -0.3f};  // along the view axis through the centre
    check_against_reference(ctx, 1, 4, pts, front_camera(32, 32), params());
    const std::vector<float> image = rasterize(ctx, {1, 4}, pts, std::vector<float>(3, 1.0f), front_camera(32, 32), params());
    const std::size_t plane = 32 * 32, centre = 16 * 32 + 16;
    CHECK(image[centre] > 0.1f);                                   // the strand is seen ...
    CHECK(std::fabs(image[plane + centre]) < 0.05f * image[centre]);  // ... with no orientation
    // The known footprint. d = (0, 0, -0.2) projects to w = J d = 0, so each segment's o2 = 0 / gamma = 0
    // and S = eps^2 J J^T + 0.3 I = (eps^2 (f/z)^2 + 0.3) I: an isotropic Gaussian at the image centre
    // (16, 16), opacity sqrt(det(J M J^T) / det S) = eps^2 (f/z)^2 / var, at depths z = 1.8, 2, 2.2,
    // composited front to back with the continuous 1/255 cut-off (confidence 1: that channel = alpha).
    const double eps2 = 0.02 * 0.02, f = 60, a_min = 1.0 / 255.0;
    for (std::uint32_t y = 0; y < 32; ++y)
      for (std::uint32_t x = 0; x < 32; ++x) {
        const double r2 = (x + 0.5 - 16) * (x + 0.5 - 16) + (y + 0.5 - 16) * (y + 0.5 - 16);
        double transmittance = 1, depth = 0;
        for (int l = 0; l < 3; ++l) {
          const double z = 2 - 0.5 * (double(pts[3 * l + 2]) + double(pts[3 * l + 5]));
          const double s0 = eps2 * (f / z) * (f / z), var = s0 + 0.3;
          const double r = std::min(0.99, s0 / var * std::exp(-0.5 * r2 / var));
          const double alpha = r < a_min ? 0.0 : (r - a_min) / (1 - a_min);
          depth += alpha * transmittance * z;
          transmittance *= 1 - alpha;
        }
        const std::size_t i = y * 32 + x;
        CAPTURE(x);
        CAPTURE(y);
        CHECK(image[i] == doctest::Approx(1 - transmittance).epsilon(1e-5));
        CHECK(image[plane + i] == 0.f);
        CHECK(image[2 * plane + i] == 0.f);
        CHECK(image[3 * plane + i] == doctest::Approx(1 - transmittance).epsilon(1e-5));
        CHECK(image[4 * plane + i] == doctest::Approx(depth).epsilon(1e-5));
      }
  }
  SUBCASE("segments behind the camera and crossing the near plane") {
    std::vector<float> pts;
    for (int k = 0; k < 8; ++k) pts.insert(pts.end(), {0.05f * k, 0.02f, 3.0f - 0.6f * k});  // z from 3 (behind) to -1.2
    check_against_reference(ctx, 1, 8, pts, front_camera(40, 30), params());
  }
  SUBCASE("strands entirely off screen give an empty image and zero gradients") {
    std::vector<float> pts;
    for (int k = 0; k < 5; ++k) pts.insert(pts.end(), {5.0f + 0.1f * k, 0, 0});
    const std::vector<float> image = rasterize(ctx, {1, 5}, pts, std::vector<float>(4, 1.0f), front_camera(16, 16), params());
    CHECK(max_abs(image) == 0.0);
    check_against_reference(ctx, 1, 5, pts, front_camera(16, 16), params());
    // Every segment is culled, so the adjoint gives it nothing: exactly 0, not just within tolerance.
    const RasterGradients g = rasterize_backward(ctx, {1, 5}, pts, std::vector<float>(4, 1.0f), front_camera(16, 16), params(),
                                                 {}, std::vector<float>(5 * 16 * 16, 1.0f));
    CHECK(max_abs(g.points) == 0.0);
    CHECK(max_abs(g.confidence) == 0.0);
  }
  SUBCASE("a 1x1 image") {
    std::vector<float> pts = {-0.1f, 0, 0, 0, 0.01f, 0, 0.1f, 0, 0};
    check_against_reference(ctx, 1, 3, pts, front_camera(1, 1, 20), params(0.05));
  }
  SUBCASE("an occluder in front of everything hides all strands") {
    std::vector<float> pts = {-0.1f, 0, 0, 0, 0.01f, 0, 0.1f, 0, 0};
    const RasterCamera cam = front_camera(24, 24);
    const std::vector<float> body(24 * 24, 1.0f);  // depth 1 < the strands' depth 2
    const std::vector<float> image = rasterize(ctx, {1, 3}, pts, std::vector<float>(2, 1.0f), cam, params(), body);
    CHECK(max_abs(image) == 0.0);
    check_against_reference(ctx, 1, 3, pts, cam, params(), body);
    // No pixel composites a hidden Gaussian, so its projected gradient stays 0 and so do the points'.
    const RasterGradients g = rasterize_backward(ctx, {1, 3}, pts, std::vector<float>(2, 1.0f), cam, params(), body,
                                                 std::vector<float>(5 * 24 * 24, 1.0f));
    CHECK(max_abs(g.points) == 0.0);
    CHECK(max_abs(g.confidence) == 0.0);
  }
  SUBCASE("more than 10,000 Gaussians in one tile") {
    const std::uint32_t strands = 180, L = 60;  // 10,620 segments inside one 16x16 tile
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> pts;
    for (std::uint32_t s = 0; s < strands; ++s) {
      float p[3] = {0.03f * u(rng), 0.03f * u(rng), 0.2f * u(rng)};
      for (std::uint32_t l = 0; l < L; ++l) {
        pts.insert(pts.end(), p, p + 3);
        for (float& x : p) x += 0.0008f * u(rng);
      }
    }
    RasterCamera cam = front_camera(16, 16, 100);
    // 10,620 layers of transmittance: float error grows with depth. On an H100 (multiply-adds
    // contracted, another summation order) the confidence adjoint was off by 1.6e-3 of its
    // largest value, against 1e-3 elsewhere.
    check_against_reference(ctx, strands, L, pts, cam, params(0.002), {}, 2e-4, 3e-3);
  }
}

TEST_CASE("a tile list longer than a device's loop limit is walked to its end") {
  // lavapipe ends any loop nest after 65,535 iterations; one tile's list here holds 80,000
  // Gaussians that reach its pixels' rectangle but stay under the 1/255 cut-off at every pixel
  // centre (so no pixel saturates and the walk goes on), between strands in front of them and
  // behind them. Walked in one pass, the strands behind were lost in the forward and those in front
  // in the adjoint; the compositing now walks such lists in passes (RasterParams::walk_chunk).
  gpu::Context& ctx = test::context();
  const RasterCamera cam = front_camera(8, 8);  // one tile; camera at z = 2, f = 60
  const std::uint32_t fillers = 800, signal = 16, L = 101;
  std::vector<float> pts;
  // Zero-length segments centred between two pixel centres of row 2 (u = 4, v = 2.5), at depth 2:
  // their opacity is the floor 0.005, so they reach the row's rectangle (the mean lies in it) while
  // alpha at the nearest centres is 0.005 exp(-0.25 / 2 / 0.3) < 1/255.
  for (std::uint32_t s = 0; s < fillers; ++s)
    for (std::uint32_t l = 0; l < L; ++l) pts.insert(pts.end(), {0.0f, 0.05f, 0.0f});
  // Horizontal strands of 4-pixel segments through the pixel-centre rows 0..3, half at depth 1.9
  // (in front of the fillers) and half at depth 2.1 (behind them).
  for (std::uint32_t s = 0; s < signal; ++s) {
    const float depth = s < signal / 2 ? 1.9f : 2.1f, row = 0.5f + float(s % 4);
    const float y = (4.0f - row) * depth / 60.0f;
    for (std::uint32_t l = 0; l < L; ++l) pts.insert(pts.end(), {(4.0f * float(l) - 200.0f + 0.5f * float(s)) * depth / 60.0f, y, 2.0f - depth});
  }
  const RasterParams rp = params(0.001);  // 0.03 px at depth 2
  std::vector<float> proj;
  project_all(pts, std::vector<float>((fillers + signal) * (L - 1), 0.7f), fillers + signal, L, cam, rp, proj);
  for (std::uint32_t i = 0; i < fillers * (L - 1); i += 997) {  // the fillers are as described
    const float* g = &proj[std::size_t(i) * kProjected];
    REQUIRE(g[kOpacity] * 255.0f > 1.0f);
    for (float py : {1.5f, 2.5f, 3.5f})
      for (float px : {3.5f, 4.5f}) REQUIRE(gaussian_alpha(g, px, py) == 0.0f);
  }
  SUBCASE("in the device's passes") { check_against_reference(ctx, fillers + signal, L, pts, cam, rp, {}, 1e-4, 2e-3); }
  SUBCASE("with a body between the fillers and the strands behind them over the top rows") {
    // The walk of the top rows' pixels may stop once a batch lies behind their body (depth 2.05):
    // the strands behind stay hidden there and seen below, as in the reference.
    std::vector<float> body(64, std::numeric_limits<float>::infinity());
    std::fill(body.begin(), body.begin() + 32, 2.05f);
    check_against_reference(ctx, fillers + signal, L, pts, cam, rp, body, 1e-4, 2e-3);
    RasterParams chunked = rp;
    chunked.walk_chunk = 5000;
    check_against_reference(ctx, fillers + signal, L, pts, cam, chunked, body, 1e-4, 2e-3);
  }
  SUBCASE("in passes of 5,000 entries") {
    RasterParams chunked = rp;
    chunked.walk_chunk = 5000;
    check_against_reference(ctx, fillers + signal, L, pts, cam, chunked, {}, 1e-4, 2e-3);
    const StrandShape shape{fillers + signal, L};
    gpu::Buffer<float> points(ctx, pts, "points"), conf(ctx, std::vector<float>(shape.segments(), 0.7f), "confidence");
    gpu::Buffer<float> image(ctx, std::size_t(kChannels) * 64, "image");
    StrandRasterizer raster(ctx);
    raster.forward(shape, points, conf, cam, chunked, {}, image);
    CHECK(raster.walk_passes() == (raster.tile_entries() + 4999) / 5000);
    CHECK(raster.tile_entries() > 80000);
  }
  // The strands behind the fillers are seen: row 0's pixels hold more than the front strands give.
  std::vector<float> front_only(pts.begin(), pts.end() - std::ptrdiff_t(signal / 2 * L * 3));
  const std::vector<float> all = rasterize(ctx, {fillers + signal, L}, pts, std::vector<float>((fillers + signal) * (L - 1), 0.7f), cam, rp);
  const std::vector<float> front = rasterize(ctx, {fillers + signal / 2, L}, front_only,
                                             std::vector<float>((fillers + signal / 2) * (L - 1), 0.7f), cam, rp);
  CHECK(all[3] > front[3] + 0.02f);
}

TEST_CASE("bad raster inputs are refused with the field named") {
  gpu::Context& ctx = test::context();
  const std::vector<float> pts = {0, 0, 0, 0.1f, 0, 0};
  RasterCamera cam = front_camera(8, 8);
  cam.near = 0;
  CHECK_THROWS_WITH_AS(rasterize(ctx, {1, 2}, pts, std::vector<float>(1, 1.0f), cam, params()), doctest::Contains("near"), InputError);
  cam = front_camera(8, 8);
  CHECK_THROWS_WITH_AS(rasterize(ctx, {1, 2}, pts, std::vector<float>(2, 1.0f), cam, params()), doctest::Contains("segment confidence"),
                       InputError);
  std::vector<float> bad = pts;
  bad[4] = std::nanf("");
  CHECK_THROWS_WITH_AS(rasterize(ctx, {1, 2}, bad, std::vector<float>(1, 1.0f), cam, params()), doctest::Contains("strand points"),
                       InputError);
  CHECK_THROWS_WITH_AS(rasterize(ctx, {1, 2}, pts, std::vector<float>(1, 1.0f), cam, params(), std::vector<float>(3, 1.0f)),
                       doctest::Contains("body depth map"), InputError);
}
