// The fur stage's views with the scene's true orientation as the target (fur.orientation_target=
// truth): the native targets hold the true map itself, the view's coarse angle is its average, and
// a scene without the maps is refused naming the file and how to make it; a view kept for a resumed
// run reads back as it was written.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/fur/fur_view_file.hpp"
#include "engine/fur/fur_views.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/io/mesh.hpp"
#include "engine/orient/orientation_io.hpp"
#include "engine/synth/synth_scene.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
namespace fs = std::filesystem;

TEST_CASE("fur views: the true orientation replaces the Gabor map, at native resolution and averaged") {
  gpu::Context& ctx = test::context();
  const fs::path dir = fs::temp_directory_path() / "nf_test_fur_views_truth";
  fs::remove_all(dir);
  synth::SynthOptions so;
  so.animal = "fox", so.views = 2, so.resolution = 192, so.strands = 60000, so.samples_per_axis = 2, so.true_orientation = true;
  synth::synthesize_scene(dir / "scene", so);
  const io::Scene scene = io::read_scene(dir / "scene");
  const geometry::Mesh bald = io::read_mesh(dir / "scene" / "gt" / "bald.ply");
  const orient::OrientationMap truth = orient::read_orientation_exr(io::find_ground_truth(dir / "scene")->orientation(scene.cameras[0].name));

  fur::FurViewOptions o;
  o.max_side = 96;  // the coarse view averages 2 x 2 photo pixels
  o.true_orientation = true;
  fur::NativeTargets native;
  const fur::FurView view = fur::make_fur_view(ctx, scene, 0, nullptr, bald, o, &native);
  // Native: the true map itself wherever the view is oriented.
  std::uint64_t compared = 0;
  for (std::uint32_t y = 0; y < native.crop.height; ++y)
    for (std::uint32_t x = 0; x < native.crop.width; ++x) {
      const std::size_t o_i = std::size_t(y) * native.crop.width + x;
      const std::uint32_t px = x + std::uint32_t(std::lround(scene.cameras[0].cx - native.crop.cx));
      const std::uint32_t py = y + std::uint32_t(std::lround(scene.cameras[0].cy - native.crop.cy));
      if (!(native.flags[o_i] & fur::NativeTargets::kOriented)) continue;
      CHECK(native.angle[o_i] == truth.orientation.at(px, py, 0));
      ++compared;
    }
  CHECK(compared > 100);
  // Coarse: the view pixel's angle is its 2 x 2 photo pixels' true angles averaged as doubled-angle
  // vectors weighted by the true weight (fur_views.hpp), the same as for a Gabor map.
  std::uint64_t coarse = 0;
  for (std::uint32_t y = 0; y < view.crop.height; ++y)
    for (std::uint32_t x = 0; x < view.crop.width; ++x) {
      const std::size_t i = std::size_t(y) * view.crop.width + x;
      const double px0 = (x - view.crop.cx) / view.scale + scene.cameras[0].cx, py0 = (y - view.crop.cy) / view.scale + scene.cameras[0].cy;
      const std::uint32_t ax = std::uint32_t(std::lround(px0)), ay = std::uint32_t(std::lround(py0));
      if (view.orientation_weight[i] < 1 || ax + 1 >= truth.orientation.width || ay + 1 >= truth.orientation.height) continue;
      double cx = 0, cy = 0;
      for (std::uint32_t dy = 0; dy < 2; ++dy)
        for (std::uint32_t dx = 0; dx < 2; ++dx) {
          const double a = truth.orientation.at(ax + dx, ay + dy, 0), c = truth.confidence.at(ax + dx, ay + dy, 0);
          cx += c * std::cos(2 * a), cy += c * std::sin(2 * a);
        }
      if (std::hypot(cx, cy) < 0.5) continue;  // no agreed angle to compare
      CHECK(std::fabs(std::remainder(view.gabor_angle[i] - 0.5 * std::atan2(cy, cx), M_PI)) < 1e-4);
      ++coarse;
    }
  CHECK(coarse > 50);
  CHECK(view.orientation_reliability > 0.3);  // the true map is coherent where strands lie side by side

  // Kept for a resumed run: read back as written, with the scene's camera; a file not whole, of
  // another camera or not a view file is made anew (nullopt), never trusted.
  const fs::path kept = dir / "camera_0.nfview";
  fur::write_fur_view(kept, view, &native.crop);
  const std::optional<fur::StoredFurView> back = fur::read_fur_view(kept, scene);
  REQUIRE(back);
  CHECK(back->view.camera == 0);
  CHECK(back->view.crop.name == scene.cameras[0].name);
  CHECK(back->view.crop.camera_to_world == view.crop.camera_to_world);
  CHECK(back->view.crop.image == scene.cameras[0].image);
  CHECK(back->view.crop.width == view.crop.width);
  CHECK(back->view.crop.cx == view.crop.cx);
  CHECK(back->view.crop.fy == view.crop.fy);
  CHECK(back->view.scale == view.scale);
  CHECK(back->view.orientation_reliability == view.orientation_reliability);
  for (auto [a, b] : {std::pair{&back->view.mask, &view.mask}, {&back->view.silhouette_weight, &view.silhouette_weight},
                      {&back->view.orientation_weight, &view.orientation_weight}, {&back->view.gabor_angle, &view.gabor_angle},
                      {&back->view.gabor_confidence, &view.gabor_confidence}, {&back->view.body_depth, &view.body_depth}, {&back->view.rgb, &view.rgb}})
    CHECK(*a == *b);
  REQUIRE(back->native_crop);
  CHECK(back->native_crop->width == native.crop.width);
  CHECK(back->native_crop->cx == native.crop.cx);
  fur::write_fur_view(dir / "no_native.nfview", view, nullptr);
  CHECK_FALSE(fur::read_fur_view(dir / "no_native.nfview", scene)->native_crop);
  CHECK_FALSE(fur::read_fur_view(dir / "missing.nfview", scene));
  fur::FurView odd = view;  // whole, but with values no view has
  odd.scale = 0;
  fur::write_fur_view(dir / "odd.nfview", odd, &native.crop);
  CHECK_FALSE(fur::read_fur_view(dir / "odd.nfview", scene));
  io::Camera empty_crop = native.crop;
  empty_crop.width = 0;
  fur::write_fur_view(dir / "odd.nfview", view, &empty_crop);
  CHECK_FALSE(fur::read_fur_view(dir / "odd.nfview", scene));
  io::Scene renamed = scene;
  renamed.cameras[0].name = "another";
  CHECK_FALSE(fur::read_fur_view(kept, renamed));
  fs::resize_file(kept, fs::file_size(kept) - 5);  // a file cut short
  CHECK_FALSE(fur::read_fur_view(kept, scene));
  std::ofstream(kept, std::ios::trunc) << "not a view";
  CHECK_FALSE(fur::read_fur_view(kept, scene));

  // Without the maps: refused, naming the file and the flag that writes it.
  fs::remove_all(dir / "scene" / "gt" / "orientation");
  CHECK_THROWS_WITH_AS(fur::make_fur_view(ctx, scene, 0, nullptr, bald, o), doctest::Contains("--true-orientation"), InputError);
  fs::remove_all(dir);
}
