// End-to-end training of the surface stage (engine/neus/neus_trainer.hpp) on a rendered capsule:
// the loop must bring the surface within a stated chamfer of the truth in a fixed number of
// steps, from the sphere initialisation (the rendering losses alone) and from the hull fit. Hard
// cases: the scene moved 1000 units away and scaled by 0.01, a camera inside the unit sphere, a
// view that sees nothing (empty mask); and checkpoints: a killed run resumes where it stopped.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "engine/geometry/marching_cubes.hpp"
#include "engine/io/image.hpp"
#include "engine/io/scene.hpp"
#include "engine/metrics/surface_metrics.hpp"
#include "engine/neus/neus_trainer.hpp"
#include "engine/neus/surface_extraction.hpp"
#include "tests/support/gpu_test.hpp"
#include "tests/support/scene_fixtures.hpp"

using namespace nf;
namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A capsule (segment a-b, radius r) placed by a similarity: world = offset + scale * local.
struct Capsule {
  glm::dvec3 a{-0.45, -0.1, 0.0}, b{0.45, 0.15, 0.05};
  double r = 0.25;
  glm::dvec3 offset{0.0};
  double scale = 1.0;
  double sdf_local(const glm::dvec3& p) const {
    const glm::dvec3 ab = b - a;
    const double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
    return glm::length(p - (a + t * ab)) - r;
  }
  double sdf(const glm::dvec3& world) const { return scale * sdf_local((world - offset) / scale); }
  glm::dvec3 centre() const { return offset + scale * 0.5 * (a + b); }
};


// Sphere-traced image and mask: a position-dependent albedo (so colour carries information),
// Lambert shading from a light at the camera, grey background.
void render(const Capsule& cap, const io::Camera& c, io::Image& rgb, io::Image& mask) {
  rgb = {c.width, c.height, 3, std::vector<float>(std::size_t(c.width) * c.height * 3, 0.3f)};
  mask = {c.width, c.height, 1, std::vector<float>(std::size_t(c.width) * c.height, 0.f)};
  const glm::dvec3 o(c.camera_to_world[3]);
  for (std::uint32_t y = 0; y < c.height; ++y)
    for (std::uint32_t x = 0; x < c.width; ++x) {
      const glm::dvec3 dc((x + 0.5 - c.cx) / c.fx, -(y + 0.5 - c.cy) / c.fy, -1.0);
      const glm::dvec3 d = glm::normalize(glm::dvec3(c.camera_to_world * glm::dvec4(dc, 0.0)));
      double t = 0;
      bool hit = false;
      for (int i = 0; i < 200 && t < 100 * cap.scale + glm::length(o - cap.centre()) * 2; ++i) {
        const double s = cap.sdf(o + t * d);
        if (s < 1e-6 * cap.scale) {
          hit = true;
          break;
        }
        t += s;
      }
      if (!hit) continue;
      const glm::dvec3 p = o + t * d, e(1e-5 * cap.scale, 0, 0);
      const glm::dvec3 n = glm::normalize(glm::dvec3(cap.sdf(p + glm::dvec3(e.x, 0, 0)) - cap.sdf(p - glm::dvec3(e.x, 0, 0)),
                                                     cap.sdf(p + glm::dvec3(0, e.x, 0)) - cap.sdf(p - glm::dvec3(0, e.x, 0)),
                                                     cap.sdf(p + glm::dvec3(0, 0, e.x)) - cap.sdf(p - glm::dvec3(0, 0, e.x))));
      const glm::dvec3 l = (p - cap.offset) / cap.scale;
      const glm::dvec3 albedo(0.55 + 0.4 * std::sin(6 * l.x), 0.5 + 0.4 * std::cos(5 * l.y + 1), 0.5 + 0.3 * std::sin(4 * l.z));
      const double shade = 0.35 + 0.65 * std::max(0.0, -glm::dot(n, d));
      const std::size_t i = std::size_t(y) * c.width + x;
      for (int k = 0; k < 3; ++k) rgb.pixels[i * 3 + k] = float(std::clamp(albedo[k] * shade, 0.0, 1.0));
      mask.pixels[i] = 1.f;
    }
}

struct Extras {
  bool inside_camera = false, blind_camera = false;
};

io::Scene write_capsule_scene(const fs::path& dir, const Capsule& cap, int views, std::uint32_t size, Extras extras) {
  fs::remove_all(dir);
  fs::create_directories(dir / "images");
  fs::create_directories(dir / "masks");
  io::Scene scene;
  scene.root = dir;
  const double dist = 3.0 * cap.scale;
  for (int i = 0; i < views; ++i) {
    const double az = 2 * kPi * i / views, el = (i % 3 - 1) * 30.0 * kPi / 180.0;
    const glm::dvec3 eye = cap.centre() + dist * glm::dvec3(std::cos(el) * std::cos(az), std::sin(el), std::cos(el) * std::sin(az));
    scene.cameras.push_back(test::pinhole_camera("v" + std::to_string(100 + i).substr(1), test::look_at(eye, cap.centre()), size, size, 35.0));
  }
  if (extras.inside_camera)  // inside the unit sphere of the normalisation, seeing part of the capsule
    scene.cameras.push_back(test::pinhole_camera("inside", test::look_at(cap.centre() + cap.scale * glm::dvec3(0.2, 0.0, 0.75), cap.centre()), size, size, 60.0));
  if (extras.blind_camera)  // looks away: an empty mask
    scene.cameras.push_back(test::pinhole_camera("blind", test::look_at(cap.centre() + dist * glm::dvec3(0, 0, 1), cap.centre() + dist * glm::dvec3(0, 0, 2)), size, size, 35.0));
  for (io::Camera& c : scene.cameras) {
    io::Image rgb, mask;
    render(cap, c, rgb, mask);
    c.image = dir / "images" / (c.name + ".png");
    c.mask = dir / "masks" / (c.name + ".png");
    io::write_png(c.image, rgb);
    io::write_png(c.mask, mask);
  }
  io::write_transforms_json(dir / "transforms.json", scene);
  return io::read_scene(dir / "transforms.json");
}

geometry::Mesh capsule_mesh(const Capsule& cap) {
  const int n = 96;
  const glm::dvec3 lo = cap.offset + cap.scale * (glm::min(cap.a, cap.b) - cap.r - 0.05);
  const glm::dvec3 hi = cap.offset + cap.scale * (glm::max(cap.a, cap.b) + cap.r + 0.05);
  const double voxel = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) / n;
  const glm::ivec3 dims = glm::ivec3(glm::ceil((hi - lo) / voxel)) + 1;
  std::vector<float> v(std::size_t(dims.x) * dims.y * dims.z);
  for (int k = 0; k < dims.z; ++k)
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i)
        v[(std::size_t(k) * dims.y + j) * dims.x + i] = float(cap.sdf(lo + glm::dvec3(i, j, k) * voxel) / cap.scale);
  // Positions relative to lo, then moved, keep float precision far from the origin.
  geometry::Mesh m = geometry::marching_cubes(v.data(), dims, glm::vec3(0.f), glm::vec3(float(voxel)), 0.f);
  for (std::size_t i = 0; i < m.positions.size(); ++i) m.positions[i] = float(double(m.positions[i]) + lo[i % 3]);
  return m;
}

struct Outcome {
  double chamfer_pct = 0, initial_chamfer_pct = 0, hull_chamfer_pct = 0, first_loss = 0, last_loss = 0, psnr = 0;
};

double chamfer_pct(const geometry::Mesh& mesh, const Capsule& cap) {
  const double cm_per_unit = 1.0 / cap.scale;  // any unit: the check is relative to the size
  const metrics::SurfaceMetrics m = metrics::surface_metrics(mesh, capsule_mesh(cap), cm_per_unit, 5.0, 20000, 1);
  const double diagonal_mm = glm::length(cap.b - cap.a + 2.0 * cap.r) * 10.0;
  return 100.0 * m.chamfer_mean_mm / diagonal_mm;
}

neus::NeusTrainingOptions small_options(std::uint32_t steps, std::uint32_t hull_fit) {
  neus::NeusTrainingOptions o;
  o.steps = steps;
  o.rays = 256;
  o.samples_per_ray = 32;
  o.warmup = 20;
  o.hull_fit_steps = hull_fit;
  o.occupancy_interval = 25;
  o.checkpoint_interval = 0;
  return o;
}

neus::NeusFieldConfig small_field() {
  neus::NeusFieldConfig f;
  f.hash = {12, 2, 15, 8, 256};
  f.sdf_hidden = {32};
  f.colour_hidden = {32};
  return f;
}

Outcome train_and_measure(const neus::NeusTrainingData& data, const Capsule& cap, const neus::NeusTrainingOptions& o) {
  neus::NeusTrainer trainer(test::context(), data, small_field(), o);
  Outcome out;
  out.initial_chamfer_pct = chamfer_pct(neus::extract_surface(trainer.field(), data.norm, data.hull, 96), cap);
  out.hull_chamfer_pct = chamfer_pct(neus::hull_surface(data.tight_hull), cap);
  trainer.train(o.steps, {}, [&](const neus::NeusStepReport& r) {
    if (r.step <= 5) out.first_loss += r.loss / 5;
    out.last_loss = r.loss, out.psnr = r.psnr;
    CHECK(std::isfinite(r.loss));
    return true;
  });
  const geometry::Mesh mesh = neus::extract_surface(trainer.field(), data.norm, data.hull, 96);
  REQUIRE(mesh.triangle_count() > 0);
  out.chamfer_pct = chamfer_pct(mesh, cap);
  MESSAGE("chamfer (% of the diagonal): initial ", out.initial_chamfer_pct, ", visual hull ", out.hull_chamfer_pct,
          ", trained ", out.chamfer_pct, "; loss ", out.first_loss, " -> ", out.last_loss, ", psnr ", out.psnr);
  return out;
}

}  // namespace

TEST_CASE("NeuS training converges on a rendered capsule, from the sphere and from the hull") {
  const Capsule cap;
  const fs::path dir = fs::temp_directory_path() / "nf_neus_training_capsule";
  const io::Scene scene = write_capsule_scene(dir, cap, 12, 80, {});
  neus::VisualHullOptions hull_options;
  hull_options.resolution = 64;
  const neus::NeusTrainingData data = neus::load_neus_training_data(scene, hull_options, 6);
  CHECK(data.held_out_views.size() == 2);

  SUBCASE("sphere initialisation, rendering losses only") {
    const Outcome r = train_and_measure(data, cap, small_options(100, 0));
    CHECK(r.last_loss < 0.6 * r.first_loss);
    CHECK(r.chamfer_pct < 1.5);
    CHECK(r.chamfer_pct < r.hull_chamfer_pct);
  }
  SUBCASE("hull fit, then rendering") {
    const Outcome r = train_and_measure(data, cap, small_options(100, 40));
    CHECK(r.chamfer_pct < 1.5);
    CHECK(r.chamfer_pct < r.hull_chamfer_pct);  // the photos improve on the masks' hull
    CHECK(r.psnr > 20.0);
  }
  fs::remove_all(dir);
}

TEST_CASE("NeuS training hard cases: far away and badly scaled, a camera inside, a blind view; resume") {
  Capsule cap;
  cap.offset = glm::dvec3(1000.0, -500.0, 250.0);
  cap.scale = 0.01;
  const fs::path dir = fs::temp_directory_path() / "nf_neus_training_far";
  const io::Scene scene = write_capsule_scene(dir, cap, 12, 80, {true, true});
  neus::VisualHullOptions hull_options;
  hull_options.resolution = 64;
  const neus::NeusTrainingData data = neus::load_neus_training_data(scene, hull_options, 0);
  CHECK(data.train_views.size() == 14);
  const Outcome r = train_and_measure(data, cap, small_options(100, 40));
  CHECK(r.chamfer_pct < 1.5);

  SUBCASE("a run killed at step 30 and resumed continues exactly where it stopped") {
    neus::NeusTrainingOptions o = small_options(60, 10);
    o.checkpoint_interval = 30;
    const fs::path ckpt = dir / "checkpoint.nfwt", again = dir / "again.nfwt", twice = dir / "twice.nfwt";
    const auto loss_at = [](neus::NeusTrainer& t, std::uint32_t until, std::uint32_t step, const fs::path& save) {
      double loss = -1;
      t.train(until, save, [&](const neus::NeusStepReport& report) {
        if (report.step == step) loss = report.loss;
        return true;
      });
      return loss;
    };
    double uninterrupted_31 = 0, uninterrupted_60 = 0;
    {
      neus::NeusTrainer t(test::context(), data, small_field(), o);
      uninterrupted_31 = loss_at(t, 60, 31, {});
      uninterrupted_60 = t.last_report().loss;
    }
    {
      neus::NeusTrainer t(test::context(), data, small_field(), o);
      loss_at(t, 30, 30, ckpt);  // "killed" after its checkpoint at step 30
    }
    neus::NeusTrainer t(test::context(), data, small_field(), o);
    REQUIRE(t.load_checkpoint(ckpt));
    CHECK(t.step() == 30);
    CHECK(t.history().size() == 3);  // the loss curve came back with it
    t.save_checkpoint(again);
    {  // save -> load -> save gives the same file: nothing is lost or changed on the way
      neus::NeusTrainer u(test::context(), data, small_field(), o);
      REQUIRE(u.load_checkpoint(again));
      u.save_checkpoint(twice);
      std::ifstream a(again, std::ios::binary), b(twice, std::ios::binary);
      const std::string bytes_a((std::istreambuf_iterator<char>(a)), {}), bytes_b((std::istreambuf_iterator<char>(b)), {});
      CHECK(bytes_a.size() > 1000);
      CHECK(bytes_a == bytes_b);
    }
    // From the same checkpoint, the first step sees the same parameters, rays and samples: its
    // forward (no atomics) gives the same loss, bit for bit.
    double other_31 = 0;
    {
      neus::NeusTrainer u(test::context(), data, small_field(), o);
      REQUIRE(u.load_checkpoint(ckpt));
      other_31 = loss_at(u, 31, 31, {});
    }
    const double resumed_31 = loss_at(t, 60, 31, {});
    CHECK(resumed_31 == other_31);
    // Against the run that was never killed, only float atomics' order in the adjoints differs.
    CHECK(resumed_31 == doctest::Approx(uninterrupted_31).epsilon(0.01));
    // Later steps differ only through float atomics' order in the adjoints.
    CHECK(t.last_report().loss == doctest::Approx(uninterrupted_60).epsilon(0.05));
    // A checkpoint written with other settings is not applied.
    neus::NeusTrainingOptions other = o;
    other.rays = 128;
    neus::NeusTrainer t2(test::context(), data, small_field(), other);
    CHECK_FALSE(t2.load_checkpoint(ckpt));
    CHECK(t2.step() == 0);
  }
  fs::remove_all(dir);
}
