// prepare's check of COLMAP's poses against the masks (silhouette_check.hpp), on a synth scene's true
// cameras and masks with poses and masks made wrong on purpose. No COLMAP: the default suite's.
#include <doctest/doctest.h>

#include <filesystem>
#include <optional>
#include <glm/gtc/matrix_transform.hpp>

#include "engine/core/error.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/io/image.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/scene.hpp"
#include "engine/prepare/silhouette_check.hpp"
#include "engine/prepare/tolerant_hull.hpp"
#include "engine/synth/synth_scene.hpp"

namespace fs = std::filesystem;
using namespace nf;

namespace {

struct Scene {
  fs::path root = fs::temp_directory_path() / "nf_test_silhouette_check";
  io::Scene scene;
  std::vector<std::vector<std::uint8_t>> masks;
  prepare::AnimalBox box;
  double radius = 0;  // half the true body's bounding diagonal
  Scene() {
    fs::remove_all(root);
    synth::SynthOptions s;
    s.animal = "dog", s.views = 24, s.resolution = 192, s.strands = 8000, s.samples_per_axis = 1;
    synth::synthesize_scene(root, s);
    scene = io::read_scene(root);
    for (const io::Camera& c : scene.cameras) masks.push_back(io::mask_of(io::read_image(c.mask)));
    // The box a layout would give: the true body's, generously grown, standing on its lowest point.
    const geometry::Bounds bounds = geometry::mesh_bounds(io::read_mesh(root / "gt" / "outer.ply"));
    const glm::dvec3 lo(bounds.lo), hi(bounds.hi);
    radius = 0.5 * glm::length(hi - lo);
    box.base = glm::dvec3(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
    box.u = {1, 0, 0}, box.v = {0, 0, 1}, box.n = {0, 1, 0};
    const double half = 0.7 * std::max(hi.x - lo.x, hi.z - lo.z);
    box.lo = {-half, -half, 0.0}, box.hi = {half, half, 1.3 * (hi.y - lo.y)};
  }
  ~Scene() { fs::remove_all(root); }
};

const Scene& scene() {
  static const Scene s;
  return s;
}

}  // namespace

TEST_CASE("the hull's grid: cubic cells over the animal's box, each centre in its own cell, nothing outside") {
  prepare::AnimalBox box;
  box.base = {1, 2, 3};
  box.u = {0, 0, 1}, box.v = {1, 0, 0}, box.n = {0, 1, 0};  // turned: the box's frame is not the world's
  box.lo = {-0.5, -0.25, 0.0}, box.hi = {0.5, 0.25, 0.4};
  const prepare::HullGrid grid(box, 20);
  CHECK(grid.side == doctest::Approx(0.05));
  CHECK(grid.cells == glm::uvec3(20, 10, 8));
  CHECK(grid.total() == 1600);
  for (std::size_t k = 0; k < grid.total(); k += 37) CHECK(grid.cell_of(grid.centre(k)) == std::optional<std::size_t>(k));
  CHECK(grid.centre(0) == box.world(box.lo + glm::dvec3(0.025)));
  CHECK_FALSE(grid.cell_of(box.world({0.0, 0.0, -0.01})));  // below the floor
  CHECK_FALSE(grid.cell_of(box.world({0.51, 0.0, 0.2})));
}

TEST_CASE("silhouette check: the true cameras and masks agree, every view") {
  const Scene& s = scene();
  const prepare::SilhouetteCheck check = prepare::check_silhouettes(s.scene.cameras, s.masks, s.box);
  REQUIRE(check.hull_voxels > 0);
  double worst = 1;
  for (const prepare::ViewSilhouette& v : check.views) {
    CHECK_FALSE(v.misplaced);
    CHECK_FALSE(v.disagrees);
    worst = std::min(worst, v.iou);
  }
  MESSAGE("true poses: median IoU ", check.median_iou, ", worst ", worst);
  CHECK(check.median_iou > 0.75);
  const json report = check.report(s.scene.cameras);
  CHECK(report["misplaced"].empty());
  CHECK(report["views"].size() == s.scene.cameras.size());
}

TEST_CASE("silhouette check: a pose moved or turned is found, a wrong mask is told apart from it") {
  const Scene& s = scene();
  std::vector<io::Camera> cameras = s.scene.cameras;
  std::vector<std::vector<std::uint8_t>> masks = s.masks;
  // View 5 moved sideways by 0.4 of the animal's radius, view 13 turned 8 degrees about its up axis
  // (a photo matched to the wrong copy of a pattern); view 19's mask is the floor, not the dog.
  io::Camera& moved = cameras[5];
  moved.camera_to_world[3] += glm::dvec4(0.4 * s.radius * glm::normalize(glm::dvec3(moved.camera_to_world[0])), 0.0);
  io::Camera& turned = cameras[13];
  turned.camera_to_world = turned.camera_to_world * glm::rotate(glm::dmat4(1.0), glm::radians(8.0), glm::dvec3(0, 1, 0));
  const io::Camera& c19 = cameras[19];
  std::fill(masks[19].begin(), masks[19].end(), 0);
  for (std::uint32_t y = c19.height * 3 / 4; y < c19.height; ++y)
    for (std::uint32_t x = 0; x < c19.width; ++x) masks[19][std::size_t(y) * c19.width + x] = 1;

  const prepare::SilhouetteCheck check = prepare::check_silhouettes(cameras, masks, s.box);
  for (std::size_t i : {std::size_t(5), std::size_t(13)}) {
    const prepare::ViewSilhouette& v = check.views[i];
    MESSAGE("view ", i, ": IoU ", v.iou, ", ", v.shifted_iou, " slid ", v.shift_px, " px; median ", check.median_iou);
    CHECK(v.misplaced);
    CHECK(v.shift_px >= 0.04 * 192);  // the least slide that refutes a pose
    CHECK(check.reason(i).find("COLMAP's pose is off") != std::string::npos);
  }
  MESSAGE("view 19 (the floor as its mask): IoU ", check.views[19].iou, ", ", check.views[19].shifted_iou, " slid");
  CHECK(check.views[19].disagrees);
  CHECK_FALSE(check.views[19].misplaced);
  CHECK(check.reason(19).empty());
  std::size_t flagged = 0;
  for (const prepare::ViewSilhouette& v : check.views) flagged += v.misplaced || v.disagrees;
  CHECK(flagged == 3);  // the other views, and the hull they carve, are unharmed
  const json report = check.report(cameras);
  CHECK(report["misplaced"].size() == 2);
  CHECK(report["disagreeing"] == json::array({cameras[19].image.filename().string()}));
}

TEST_CASE("silhouette check: views refuted before (empty masks) neither carve the hull nor are judged") {
  // Five views' poses refuted by the floor, their masks empty (the automatic masks cut them
  // nowhere): taking part, each would cost the hull a view of its tolerance of a fifth, and be named.
  const Scene& s = scene();
  std::vector<std::vector<std::uint8_t>> masks = s.masks;
  std::vector<char> left_out(masks.size(), 0);
  for (std::size_t i : {std::size_t(2), std::size_t(7), std::size_t(11), std::size_t(16), std::size_t(21)}) {
    std::fill(masks[i].begin(), masks[i].end(), 0);
    left_out[i] = 1;
  }
  const prepare::SilhouetteCheck taking_part = prepare::check_silhouettes(s.scene.cameras, masks, s.box);
  const prepare::SilhouetteCheck check = prepare::check_silhouettes(s.scene.cameras, masks, s.box, {}, &left_out);
  MESSAGE("hull voxels: ", check.hull_voxels, " with the refuted views left out, ", taking_part.hull_voxels, " with their empty masks carving");
  CHECK(check.hull_voxels > taking_part.hull_voxels);
  std::size_t flagged = 0;
  for (std::size_t i = 0; i < masks.size(); ++i) {
    CHECK(check.views[i].left_out == bool(left_out[i]));
    flagged += check.views[i].misplaced || check.views[i].disagrees;
  }
  CHECK(flagged == 0);
  CHECK(check.median_iou > 0.75);
  const json report = check.report(s.scene.cameras);
  CHECK(report["disagreeing"].empty());
  CHECK(report["views"][s.scene.cameras[7].image.filename().string()]["left_out"] == true);
}

TEST_CASE("silhouette check: a mask of another size than its photo is named") {
  const Scene& s = scene();
  std::vector<std::vector<std::uint8_t>> masks = s.masks;
  masks[3].resize(100);
  CHECK_THROWS_WITH_AS(prepare::check_silhouettes(s.scene.cameras, masks, s.box),
                       doctest::Contains(("the mask of " + s.scene.cameras[3].image.filename().string() + " has 100 pixels").c_str()), InputError);
}

TEST_CASE("silhouette check: views that share no volume conclude nothing") {
  const Scene& s = scene();
  std::vector<std::vector<std::uint8_t>> empty = s.masks;
  for (auto& m : empty) std::fill(m.begin(), m.end(), 0);
  const prepare::SilhouetteCheck check = prepare::check_silhouettes(s.scene.cameras, empty, s.box);
  CHECK(check.hull_voxels == 0);
  for (const prepare::ViewSilhouette& v : check.views) CHECK_FALSE((v.misplaced || v.disagrees));
}
TEST_CASE("silhouette check: how small a wrong pose it refutes") {
  // Measured at 192 px: a move of 0.05 radii slides the animal 4.8 px and a turn of 1 degree 4.8 px,
  // under the least slide (4 % of 192 px) and so not refuted (COLMAP's own scatter is of that
  // order); 0.1 radii and 2 degrees (9.6 px) and beyond are.
  const Scene& s = scene();
  for (const double move : {0.05, 0.1, 0.2, 0.3}) {
    std::vector<io::Camera> cameras = s.scene.cameras;
    io::Camera& moved = cameras[5];
    moved.camera_to_world[3] += glm::dvec4(move * s.radius * glm::normalize(glm::dvec3(moved.camera_to_world[0])), 0.0);
    const prepare::ViewSilhouette v = prepare::check_silhouettes(cameras, s.masks, s.box).views[5];
    CHECK_MESSAGE(v.misplaced == (move >= 0.1), "moved ", move, " radii: IoU ", v.iou, ", slid ", v.shift_px, " px");
  }
  for (const double degrees : {1.0, 2.0, 4.0}) {
    std::vector<io::Camera> cameras = s.scene.cameras;
    io::Camera& turned = cameras[13];
    turned.camera_to_world = turned.camera_to_world * glm::rotate(glm::dmat4(1.0), glm::radians(degrees), glm::dvec3(0, 1, 0));
    const prepare::ViewSilhouette v = prepare::check_silhouettes(cameras, s.masks, s.box).views[13];
    CHECK_MESSAGE(v.misplaced == (degrees >= 2.0), "turned ", degrees, " degrees: IoU ", v.iou, ", slid ", v.shift_px, " px");
  }
}
