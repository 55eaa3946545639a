// nf_gpu prepare against the truth: a synth scene with a textured floor and wall (COLMAP needs
// features off the animal), its photos and masks given without cameras. COLMAP (a real subprocess)
// must place every photo; after the best similarity transform the cameras must lie within the
// issue's bounds of the true ones, and the undistorted masks must agree with the true masks. Bad
// input must be refused with a message saying what to do, and nothing is left behind.
#include <doctest/doctest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>

#include "engine/core/error.hpp"
#include "engine/io/image.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/scene.hpp"
#include "engine/prepare/prepare_scene.hpp"
#include "engine/synth/synth_scene.hpp"

namespace fs = std::filesystem;
using namespace nf;

namespace {

Eigen::Vector3d vec(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

Eigen::Matrix3d rotation(const io::Camera& c) {
  Eigen::Matrix3d r;
  for (int col = 0; col < 3; ++col)
    for (int row = 0; row < 3; ++row) r(row, col) = c.camera_to_world[col][row];
  return r;
}

// The true mask's value where a prepared (undistorted, possibly cropped) pinhole pixel looks: both
// are pinholes of the same lens once undistorted, so the ray through the pixel maps by intrinsics.
bool true_inside(const io::Camera& prepared, const io::Camera& truth, const std::vector<std::uint8_t>& mask, std::uint32_t x, std::uint32_t y) {
  const double u = (x + 0.5 - prepared.cx) / prepared.fx * truth.fx + truth.cx, v = (y + 0.5 - prepared.cy) / prepared.fy * truth.fy + truth.cy;
  if (u < 0 || v < 0 || u >= truth.width || v >= truth.height) return false;
  return mask[std::size_t(v) * truth.width + std::size_t(u)] != 0;
}

struct Agreement {
  double worst_angle_deg = 0, worst_centre = 0, worst_iou = 1, median_iou = 0;
  double up_error_deg = 0;  // the prepared scene's +y against the truth's (synth scenes are y-up)
};

// The prepared cameras against the truth after the best similarity transform (Umeyama on the
// centres), the centres' error as a share of the animal's radius; the masks by IoU.
Agreement compare(const io::Scene& prepared, const io::Scene& truth, const fs::path& truth_root) {
  std::map<std::string, const io::Camera*> by_name;
  for (const io::Camera& c : truth.cameras) by_name[c.name] = &c;
  Eigen::Matrix3Xd from(3, prepared.cameras.size()), to(3, prepared.cameras.size());
  for (std::size_t i = 0; i < prepared.cameras.size(); ++i) {
    REQUIRE(by_name.count(prepared.cameras[i].name));
    from.col(Eigen::Index(i)) = vec(prepared.cameras[i].centre());
    to.col(Eigen::Index(i)) = vec(by_name[prepared.cameras[i].name]->centre());
  }
  const Eigen::Matrix4d similarity = Eigen::umeyama(from, to, true);
  const Eigen::Matrix3d scaled = similarity.topLeftCorner<3, 3>();
  const Eigen::Matrix3d align = scaled / std::cbrt(scaled.determinant());
  Agreement r;
  r.up_error_deg = std::acos(std::clamp((align * Eigen::Vector3d::UnitY()).dot(Eigen::Vector3d::UnitY()), -1.0, 1.0)) * 180 / M_PI;
  // The scene's radius: the true animal's bounding sphere around its box's centre.
  const geometry::Mesh outer = io::read_mesh(truth_root / "gt" / "outer.ply");
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e30), hi = -lo;
  for (std::size_t v = 0; v < outer.vertex_count(); ++v)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], double(outer.positions[3 * v + a])), hi[a] = std::max(hi[a], double(outer.positions[3 * v + a]));
  double radius = 0;
  for (std::size_t v = 0; v < outer.vertex_count(); ++v)
    radius = std::max(radius, (Eigen::Vector3d(outer.positions[3 * v], outer.positions[3 * v + 1], outer.positions[3 * v + 2]) - 0.5 * (lo + hi)).norm());

  std::vector<double> ious;
  for (const io::Camera& p : prepared.cameras) {
    const io::Camera& t = *by_name[p.name];
    const Eigen::Matrix3d d = (align * rotation(p)).transpose() * rotation(t);
    r.worst_angle_deg = std::max(r.worst_angle_deg, std::acos(std::clamp((d.trace() - 1) / 2, -1.0, 1.0)) * 180 / M_PI);
    const Eigen::Vector3d c = (similarity * vec(p.centre()).homogeneous()).head<3>();
    r.worst_centre = std::max(r.worst_centre, (c - vec(t.centre())).norm() / radius);
    const std::vector<std::uint8_t> pm = io::mask_of(io::read_image(p.mask)), tm = io::mask_of(io::read_image(t.mask));
    std::size_t both = 0, either = 0;
    for (std::uint32_t y = 0; y < p.height; ++y)
      for (std::uint32_t x = 0; x < p.width; ++x) {
        const bool a = pm[std::size_t(y) * p.width + x] != 0, b = true_inside(p, t, tm, x, y);
        both += a && b, either += a || b;
      }
    ious.push_back(either ? double(both) / double(either) : 1.0);
  }
  std::sort(ious.begin(), ious.end());
  r.worst_iou = ious.front(), r.median_iou = ious[ious.size() / 2];
  return r;
}

// One textured synth scene for the cases below. The default suite's is small (320 px: a minute of
// COLMAP); NF_TEST_PREPARE_FULL=1 (label long) makes the issue's: a cat at 512 px.
struct Fixture {
  bool full = std::getenv("NF_TEST_PREPARE_FULL") != nullptr;
  fs::path root = fs::temp_directory_path() / (full ? "nf_test_prepare_full" : "nf_test_prepare");
  io::Scene truth;
  Fixture() {
    fs::remove_all(root);
    synth::SynthOptions s;
    s.animal = full ? "cat" : "dog", s.views = 36, s.resolution = full ? 512 : 320, s.strands = full ? 100000 : 20000;
    s.samples_per_axis = full ? 3 : 2, s.backdrop = "textured";
    synth::synthesize_scene(root / "truth", s);
    truth = io::read_scene(root / "truth");
  }
  ~Fixture() { fs::remove_all(root); }
  prepare::PrepareOptions options(const char* out) const {
    prepare::PrepareOptions o;
    o.images = root / "truth" / "images", o.out = root / out;
    o.max_features = full ? 4096 : 2048;
    return o;
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

}  // namespace

TEST_CASE("prepare places every photo of a textured synth scene near the true cameras, masks with them") {
  // The small scene's bounds are looser than the issue's, which the full one checks: within 0.5
  // degrees and 1 % of the animal's radius. COLMAP's threads make each run differ a little.
  const Fixture& f = fixture();
  // At 320 px COLMAP's radial distortion varies from run to run (k 0.002 in one, larger in another,
  // which took the masks' IoU to 0.94 and the centres to 2.8 %).
  const double max_angle_deg = f.full ? 0.5 : 1.0, max_centre = f.full ? 0.01 : 0.04, min_iou = f.full ? 0.97 : 0.92;
  prepare::PrepareOptions o = f.options("prepared");
  o.masks = f.root / "truth" / "masks";
  o.cm_per_unit = 2.5;
  const json report = prepare::prepare_scene(o);
  CHECK(report["placed"] == 36);
  CHECK(report["not_placed"].empty());
  CHECK(report["masks"] == "given");
  CHECK(report["reprojection_error_px"].get<double>() < 1.0);
  CHECK_FALSE(fs::exists(f.root / "prepared.partial"));
  const io::Scene prepared = io::read_scene(o.out);
  REQUIRE(prepared.cameras.size() == f.truth.cameras.size());
  CHECK(prepared.cm_per_unit == 2.5);
  prepared.check_files("prepared");
  CHECK(fs::exists(o.out / "previews" / "000.jpg"));
  const Agreement a = compare(prepared, f.truth, f.root / "truth");
  MESSAGE("prepare: lens ", report["cameras"].dump(), "; worst rotation error ", a.worst_angle_deg, " deg, worst centre error ", 100 * a.worst_centre, " % of the radius, up ", a.up_error_deg, " deg off, mask IoU median ",
          a.median_iou, " worst ", a.worst_iou, ", ", report["seconds"]["total"].get<double>(), " s");
  CHECK(a.worst_angle_deg < max_angle_deg);
  CHECK(report["frame"]["up_from"] == "floor");
  CHECK(a.up_error_deg < 1.0);  // written upright
  CHECK(a.worst_centre < max_centre);
  CHECK(a.worst_iou > min_iou);

  // Bad input: each says what to do, and nothing is written.
  CHECK_THROWS_WITH_AS(prepare::prepare_scene(o), doctest::Contains("exists; name a new folder"), UsageError);
  const fs::path few = f.root / "few";
  fs::create_directories(few);
  for (const char* name : {"000.png", "001.png"}) fs::copy_file(o.images / name, few / name);
  std::ofstream(few / "notes.txt") << "not a photo\n";
  prepare::PrepareOptions bad = o;
  bad.images = few, bad.out = f.root / "few_out";
  CHECK_THROWS_WITH_AS(prepare::prepare_scene(bad), doctest::Contains("COLMAP needs at least 3 overlapping photos"), InputError);
  fs::copy_file(o.images / "002.png", few / "002.png");
  bad.masks = f.root / "truth" / "gt";
  CHECK_THROWS_WITH_AS(prepare::prepare_scene(bad), doctest::Contains("no mask for 000.png"), InputError);
  bad.masks = o.masks;
  setenv("NF_COLMAP", (f.root / "no-colmap").c_str(), 1);
  CHECK_THROWS_WITH_AS(prepare::prepare_scene(bad), doctest::Contains("NF_COLMAP names"), UsageError);
  unsetenv("NF_COLMAP");
  CHECK_FALSE(fs::exists(bad.out));
}

TEST_CASE("prepare makes the masks itself when the photos have none, close to the true masks") {
  // The bounds (median IoU >= 0.95, worst >= 0.90) on the full scene; the small scene's
  // outlines are a larger share of its masks, and its 24-33 animal points vary with COLMAP's run
  // (320 px: median 0.917-0.935, worst 0.89-0.91 measured).
  const Fixture& f = fixture();
  const double min_median = f.full ? 0.95 : 0.88, min_worst = f.full ? 0.90 : 0.80;
  const prepare::PrepareOptions o = f.options("automatic");
  const json report = prepare::prepare_scene(o);
  CHECK(report["masks"] == "automatic");
  CHECK(report["automatic_masks"]["floor_found"] == true);
  const io::Scene prepared = io::read_scene(o.out);
  REQUIRE(prepared.cameras.size() == f.truth.cameras.size());
  const Agreement a = compare(prepared, f.truth, f.root / "truth");
  MESSAGE("automatic masks: IoU median ", a.median_iou, " worst ", a.worst_iou, ", ", report["automatic_masks"]["seconds"].get<double>(), " s; ",
          report["automatic_masks"]["animal_points"].get<std::size_t>(), " animal points, ", report["automatic_masks"]["disagreeing_views"].size(),
          " views flagged");
  CHECK(a.median_iou >= min_median);
  CHECK(a.worst_iou >= min_worst);
  CHECK(fs::exists(o.out / "previews" / "000.jpg"));
}
