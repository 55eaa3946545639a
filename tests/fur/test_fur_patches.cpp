// Native-resolution patches (engine/fur/fur_patches): what is cut is what was stored (up to the
// file's quantisation), the patch's camera is the view's shifted, patches are placed on the fur in
// proportion to its area and visit all of it, small views come whole, a lost file is an error
// naming it, and the store leaves nothing behind.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <optional>

#include "engine/core/error.hpp"
#include "engine/fur/fur_patches.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::fur;
namespace fs = std::filesystem;

namespace {

// A camera at the origin looking down -z (OpenGL axes) with `width` x `height` pixels.
io::Camera camera(std::uint32_t width, std::uint32_t height) {
  io::Camera c;
  c.name = "patch_test", c.width = width, c.height = height;
  c.fx = c.fy = 200, c.cx = width / 2.0, c.cy = height / 2.0;
  return c;
}

// A quad at depth 2 filling the view: the body the patches' depth is rasterised from.
geometry::Mesh wall() {
  geometry::Mesh m;
  m.positions = {-50, -50, -2, 50, -50, -2, 50, 50, -2, -50, 50, -2};
  m.triangles = {0, 1, 2, 0, 2, 3};
  return m;
}

// Fur in two discs of radius 30 and 15 px (areas 4:1), the mask a little wider than the fur, the
// angle and reliability a function of the pixel.
NativeTargets two_discs(std::uint32_t width, std::uint32_t height) {
  NativeTargets t;
  t.crop = camera(width, height);
  const std::uint64_t n = t.pixels();
  t.flags.assign(n, 0), t.angle.assign(n, 0.f), t.confidence.assign(n, 0.f), t.scale.assign(n, 0);
  for (std::uint32_t y = 0; y < height; ++y)
    for (std::uint32_t x = 0; x < width; ++x) {
      const std::size_t i = std::size_t(y) * width + x;
      const double a = std::hypot(x - 80.0, y - 90.0), b = std::hypot(x - 300.0, y - 120.0);
      const bool fur = a < 30 || b < 15, mask = a < 33 || b < 18;
      t.flags[i] = std::uint8_t((mask ? NativeTargets::kMask : 0) | (fur ? NativeTargets::kFur : 0) |
                                (a < 25 || b < 10 ? NativeTargets::kOriented : 0));
      t.angle[i] = float(std::fmod(0.01 * x + 0.02 * y, M_PI));
      t.confidence[i] = fur ? float((x % 7) / 6.0) : 0.f;
      t.scale[i] = std::uint8_t(x % 2);
    }
  return t;
}

}  // namespace

TEST_CASE("fur patches: a patch reads back the stored targets at the view's camera shifted to the patch") {
  gpu::Context& ctx = test::context();
  const fs::path dir = fs::temp_directory_path() / "nf_test_fur_patches_read";
  fs::remove_all(dir);
  const geometry::Mesh body = wall();
  const NativeTargets t = two_discs(360, 200);
  {
    FurPatches store(ctx, body, dir, 64);
    REQUIRE(store.add(7, t) == 0);
    CHECK(store.size() == 1);
    CHECK(store.camera(0) == 7);
    CHECK(store.bytes_on_disk() == 360u * 200u * 4u);
    CHECK(store.scale_share().size() == 2);
    const PatchPlace p{50, 60, 64, 40};
    const FurView v = store.cut(0, p);
    REQUIRE(v.pixels() == 64u * 40u);
    CHECK(v.crop.cx == doctest::Approx(t.crop.cx - 50));
    CHECK(v.crop.cy == doctest::Approx(t.crop.cy - 60));
    CHECK(v.crop.fx == t.crop.fx);
    for (std::uint32_t y = 0; y < p.height; ++y)
      for (std::uint32_t x = 0; x < p.width; ++x) {
        const std::size_t o = std::size_t(y) * p.width + x, i = std::size_t(y + p.y0) * t.crop.width + x + p.x0;
        const std::uint8_t f = t.flags[i];
        REQUIRE(v.mask[o] == ((f & NativeTargets::kMask) ? 1.f : 0.f));
        REQUIRE(v.silhouette_weight[o] == ((f & NativeTargets::kMask) && !(f & NativeTargets::kFur) ? 0.f : 1.f));
        REQUIRE(v.orientation_weight[o] == ((f & NativeTargets::kOriented) ? 1.f : 0.f));
        const double d = std::abs(double(v.gabor_angle[o]) - t.angle[i]);
        REQUIRE(std::min(d, M_PI - d) <= M_PI / 131072 + 1e-6);  // half a step of 65,536 over pi, mod pi
        REQUIRE(std::abs(v.gabor_confidence[o] - t.confidence[i]) <= 0.5f / 255.f + 1e-6f);
        REQUIRE(v.body_depth[o] == doctest::Approx(2.0).epsilon(1e-4));  // the wall, seen through the patch's camera
      }
    // The orientation loss's scale: the mean reliability over the oriented fur.
    // (Of the stored reliabilities, in 1/255: a reopened store computes the same.)
    double sum = 0, count = 0;
    for (std::size_t i = 0; i < t.flags.size(); ++i)
      if (t.flags[i] & NativeTargets::kOriented) sum += std::lround(t.confidence[i] * 255.f) / 255.0, count += 1;
    CHECK(store.orientation_reliability(0) == doctest::Approx(sum / count).epsilon(1e-9));
    CHECK(v.orientation_reliability == store.orientation_reliability(0));
    // A lost file is an error naming it, not a crash or zeros.
    for (const auto& e : fs::directory_iterator(dir)) fs::remove(e.path());
    try {
      store.cut(0, p);
      FAIL("a removed file was read");
    } catch (const InputError& e) {
      CHECK(std::string(e.what()).find("camera_7.nftargets") != std::string::npos);
    }
  }
  CHECK_FALSE(fs::exists(dir));  // the store removes its folder
}

TEST_CASE("fur patches: placed on the fur in proportion to its area, every part of it visited, the same for the same seed") {
  gpu::Context& ctx = test::context();
  const fs::path dir = fs::temp_directory_path() / "nf_test_fur_patches_place";
  fs::remove_all(dir);
  const geometry::Mesh body = wall();
  const NativeTargets t = two_discs(360, 200);
  FurPatches store(ctx, body, dir, 48);
  store.add(0, t);
  const std::uint32_t W = t.crop.width;
  std::vector<std::uint8_t> seen(t.flags.size(), 0);
  std::size_t big = 0, small = 0;
  const std::size_t draws = 400;
  for (std::size_t k = 0; k < draws; ++k) {
    const PatchPlace p = store.place(0, 1000 + k);
    REQUIRE(p.width == 48);
    REQUIRE(p.height == 48);
    REQUIRE(p.x0 + p.width <= t.crop.width);
    REQUIRE(p.y0 + p.height <= t.crop.height);
    REQUIRE(p == store.place(0, 1000 + k));
    const double cx = p.x0 + 24.0, cy = p.y0 + 24.0;
    (std::hypot(cx - 80, cy - 90) < std::hypot(cx - 300, cy - 120) ? big : small) += 1;
    for (std::uint32_t y = p.y0; y < p.y0 + p.height; ++y)
      for (std::uint32_t x = p.x0; x < p.x0 + p.width; ++x) seen[std::size_t(y) * W + x] = 1;
  }
  // The discs' fur areas are 4:1: about 80 % of the patches on the big one.
  CHECK(double(big) / draws == doctest::Approx(0.8).epsilon(0.08));
  CHECK(small > 0);
  std::size_t fur = 0, visited = 0;
  for (std::size_t i = 0; i < t.flags.size(); ++i)
    if (t.flags[i] & NativeTargets::kFur) ++fur, visited += seen[i];
  CHECK(visited == fur);
  // Scoring places: repeats dropped; a view that fits in a patch comes whole, once.
  CHECK(store.places(0, 6, 9).size() == 6);
  FurPatches whole(ctx, body, dir / "whole", 512);
  whole.add(0, t);
  const std::vector<PatchPlace> one = whole.places(0, 4, 9);
  REQUIRE(one.size() == 1);
  CHECK(one[0] == PatchPlace{0, 0, 360, 200});
  CHECK_THROWS_AS(FurPatches(ctx, body, dir / "tiny", 8), InputError);
}

TEST_CASE("fur patches: a kept store's files are reopened by a later store with the same places, cuts and figures; a file not whole is not") {
  gpu::Context& ctx = test::context();
  const fs::path dir = fs::temp_directory_path() / "nf_test_fur_patches_kept";
  fs::remove_all(dir);
  const geometry::Mesh body = wall();
  const NativeTargets t = two_discs(360, 200);
  NativeTargets other = two_discs(200, 120);
  other.crop.name = "other";
  std::vector<PatchPlace> places;
  FurView cut;
  double reliability = 0;
  std::vector<double> share;
  {
    FurPatches store(ctx, body, dir, 48, FurPatches::Files::kept);
    store.add(3, t);
    store.add(5, other);
    CHECK_THROWS(store.add(3, t));  // one file per camera
    places = store.places(0, 8, 21);
    cut = store.cut(0, places[2]);
    reliability = store.orientation_reliability(0), share = store.scale_share();
  }
  REQUIRE(fs::exists(dir / "camera_3.nftargets"));  // kept when the store goes
  {
    FurPatches again(ctx, body, dir, 48);
    REQUIRE(again.reopen(3, t.crop) == std::optional<std::uint32_t>(0));
    CHECK(again.camera(0) == 3);
    CHECK(again.places(0, 8, 21) == places);
    CHECK(again.orientation_reliability(0) == reliability);
    CHECK(again.fur_pixels(0) > 0);
    const FurView v = again.cut(0, places[2]);
    CHECK(v.gabor_angle == cut.gabor_angle);
    CHECK(v.gabor_confidence == cut.gabor_confidence);
    CHECK(v.orientation_weight == cut.orientation_weight);
    CHECK(v.silhouette_weight == cut.silhouette_weight);
    CHECK(!again.reopen(4, t.crop));        // no file for that camera
    CHECK(!again.reopen(5, t.crop));        // a file of another size than the crop
    fs::resize_file(dir / "camera_5.nftargets", 1000);  // a run killed while writing it
    CHECK(!again.reopen(5, other.crop));
    again.add(5, other);                    // made anew
    CHECK(again.scale_share() == share);    // the scales of both views counted once each
  }
  CHECK_FALSE(fs::exists(dir));  // removed by the store that did not keep them
}
