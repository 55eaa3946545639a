// Synthetic scenes: fur grown as the knowledge says, an independent renderer whose coverage matches
// analytic areas, and a written scene whose ground-truth strand roots project into the masks through
// every camera reader (transforms.json, and NeuS / Artemis / COLMAP files written from the same
// cameras).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/body/quadruped.hpp"
#include "engine/core/error.hpp"
#include "engine/core/stats.hpp"
#include "engine/geometry/marching_cubes.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/io/image.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/scene.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/synth/camera_rig.hpp"
#include "engine/synth/fur_growth.hpp"
#include "engine/synth/strand_renderer.hpp"
#include "engine/synth/synth_scene.hpp"
#include "tests/support/scene_fixtures.hpp"

using namespace nf;
namespace fs = std::filesystem;
using body::Region;

namespace {

glm::vec3 at(const std::vector<float>& xyz, std::size_t i) { return {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]}; }

// The fraction of points whose pixel is inside the camera's mask.
double fraction_in_masks(const io::Scene& scene, const std::vector<glm::vec3>& points) {
  std::uint64_t inside = 0, total = 0;
  for (const io::Camera& cam : scene.cameras) {
    REQUIRE(!cam.mask.empty());
    const io::Image mask_image = io::read_image(cam.mask);
    const auto mask = io::mask_of(mask_image);
    for (const glm::vec3& p : points) {
      const glm::dvec3 uvd = cam.project(glm::dvec3(p));
      ++total;
      if (uvd.z <= 0) continue;  // behind the camera: not in the mask
      const double u = std::floor(uvd.x), v = std::floor(uvd.y);
      if (u < 0 || v < 0 || u >= cam.width || v >= cam.height) continue;
      inside += mask[std::size_t(v) * cam.width + std::size_t(u)];
    }
  }
  REQUIRE(total > 0);
  return double(inside) / double(total);
}

// 200 x 200 pixels, focal length 400 px, 2 units in front of the origin looking down -z at it.
io::Camera front_camera() {
  io::Camera cam;
  cam.name = "front";
  cam.width = cam.height = 200;
  cam.fx = cam.fy = 400, cam.cx = cam.cy = 100;
  cam.camera_to_world = glm::translate(glm::dmat4(1.0), glm::dvec3(0, 0, 2));
  return cam;
}

}  // namespace

TEST_CASE("fur grows as the knowledge says: lengths per region, nothing on bald regions, outside the skin") {
  const auto p = body::animal_proportions("fox");
  const body::BodyModel model = body::build_quadruped(p, {p.torso_length / 70});
  const geometry::Mesh skin = body::pose_body(model, {});
  const knowledge::Knowledge know = knowledge::preset("fox");
  synth::GrowOptions o;
  o.strand_count = 20000, o.points_per_strand = 32, o.seed = 3, o.animal = "fox", o.torso_length = p.torso_length;
  const synth::Fur fur = synth::grow_fur(skin, know, synth::fur_style("fox"), o);
  REQUIRE(fur.strands.strand_count() == 20000);
  CHECK_NOTHROW(fur.strands.validate("fur"));

  std::map<int, std::pair<double, int>> lengths;
  const geometry::PointIndex skin_index(skin.positions);
  std::uint64_t below = 0, points = 0;
  double root_gap = 0, along = 0;
  int along_count = 0;
  for (std::uint32_t s = 0; s < fur.strands.strand_count(); ++s) {
    const Region region = static_cast<Region>(fur.strands.regions[s]);
    REQUIRE(know.grows_fur(region));
    double len = 0;
    const std::uint32_t first = fur.strands.offsets[s];
    for (std::uint32_t k = first + 1; k < fur.strands.offsets[s + 1]; ++k) {
      const glm::vec3 q = at(fur.strands.points, k);
      len += glm::distance(q, at(fur.strands.points, k - 1));
      const auto [i, d2] = skin_index.nearest(&fur.strands.points[3 * k]);
      (void)d2;
      const glm::vec3 n = at(skin.normals, i);
      below += glm::dot(q - at(skin.positions, i), n) < -0.002f * p.torso_length;
      ++points;
    }
    lengths[int(region)].first += len, ++lengths[int(region)].second;
    root_gap = std::max(root_gap, double(std::sqrt(skin_index.nearest(&fur.strands.points[3 * first]).second)));
    if (region == Region::body) {  // the first segment follows the growth direction in the tangent plane
      const glm::vec3 d = glm::normalize(at(fur.strands.points, first + 1) - at(fur.strands.points, first));
      const glm::vec3 n = fur.root_normals[s];
      const glm::vec3 g = know.at(region).direction;
      const glm::vec3 gt = g - glm::dot(g, n) * n, dt = d - glm::dot(d, n) * n;
      if (glm::length(gt) > 0.3f) along += glm::dot(glm::normalize(dt), glm::normalize(gt)), ++along_count;
    }
  }
  for (const auto& [region_id, sum] : lengths) {
    const int region = region_id;  // clang 14 cannot capture a structured binding (CAPTURE is a lambda)
    CAPTURE(body::kRegionNames[std::size_t(region)]);
    const double expected = know.at(static_cast<Region>(region)).length_cm / 100.0;
    if (sum.second > 50) CHECK(sum.first / sum.second == doctest::Approx(expected).epsilon(0.05));
  }
  CHECK(lengths.count(int(Region::eyes)) == 0);
  CHECK(lengths.count(int(Region::nosetip)) == 0);
  CHECK(lengths.count(int(Region::tail)) == 1);
  CHECK(double(below) / double(points) < 0.01);
  CHECK(root_gap < p.torso_length / 70);  // roots lie on the skin (within a voxel of a vertex)
  REQUIRE(along_count > 100);
  CHECK(along / along_count > 0.8);
}

TEST_CASE("the renderer's coverage matches analytic areas") {
  const io::Camera cam = front_camera();

  // A sphere of radius 0.25 at the origin: its silhouette is a disc of radius f r / sqrt(d^2 - r^2).
  const int n = 64;
  std::vector<float> field(std::size_t(n) * n * n);
  const float voxel = 0.7f / (n - 1);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        field[(std::size_t(z) * n + y) * n + x] = glm::length(glm::vec3(x, y, z) * voxel - 0.35f) - 0.25f;
  geometry::Mesh sphere = geometry::marching_cubes(field.data(), glm::ivec3(n), glm::vec3(0), glm::vec3(voxel), 0.0f);
  for (std::size_t i = 0; i < sphere.positions.size(); ++i) sphere.positions[i] -= 0.35f;
  geometry::compute_vertex_normals(sphere);
  synth::RenderOptions options;
  options.samples_per_axis = 4;
  {
    const synth::StrandRenderer renderer(sphere, {}, io::StrandSet{}, {}, options);
    const synth::Rendered r = renderer.render(cam);
    double covered = 0;
    for (float c : r.coverage.pixels) covered += c;
    const double radius_px = 400 * 0.25 / std::sqrt(4 - 0.0625);
    CHECK(covered == doctest::Approx(3.14159265 * radius_px * radius_px).epsilon(0.02));
  }
  // One straight strand across the view, no body: covers 2 r x length (pixels).
  std::vector<float> xyz;
  for (int k = 0; k < 100; ++k) xyz.insert(xyz.end(), {-0.1f + 0.2f * k / 99.0f, 0.02f, 0.0f});
  const io::StrandSet strand = io::StrandSet::uniform(1, 100, xyz);
  synth::StrandLook look;
  look.radius = 0.004f;  // 1.6 px wide
  const synth::StrandRenderer renderer(geometry::Mesh{}, {}, strand, look, options);
  const synth::Rendered r = renderer.render(cam);
  double covered = 0;
  for (float c : r.coverage.pixels) covered += c;
  const double length_px = 0.2 * 400 / 2, width_px = 2 * 0.004 * 400 / 2;
  CHECK(covered == doctest::Approx(length_px * width_px + 3.14159265 * width_px * width_px / 4).epsilon(0.05));
}

TEST_CASE("the true orientation map reads each strand's direction on screen, agreed where a strand covers the pixel") {
  const io::Camera cam = front_camera();
  // A horizontal strand at y = 0.0525 (on screen: 0 degrees, rows 85.5-93.5) and one along (1, 1) through (0.05, -0.05)
  // (up and to the right on screen: 45 degrees).
  std::vector<float> xyz;
  for (int k = 0; k < 100; ++k) xyz.insert(xyz.end(), {-0.1f + 0.2f * k / 99.0f, 0.0525f, 0.0f});
  for (int k = 0; k < 100; ++k) xyz.insert(xyz.end(), {0.1f * k / 99.0f, -0.1f + 0.1f * k / 99.0f, 0.0f});
  const io::StrandSet strands = io::StrandSet::uniform(2, 100, xyz);
  synth::StrandLook look;
  look.radius = 0.02f;  // 8 px wide
  synth::RenderOptions options;
  CHECK(synth::StrandRenderer(geometry::Mesh{}, {}, strands, look, options).render(cam).orientation.pixels.empty());
  options.true_orientation = true;
  const synth::Rendered r = synth::StrandRenderer(geometry::Mesh{}, {}, strands, look, options).render(cam);
  REQUIRE(r.orientation.channels == 2);
  REQUIRE(r.orientation.width == 200);
  const auto angle_deg = [&](std::uint32_t x, std::uint32_t y) { return r.orientation.at(x, y, 0) * 180.0 / 3.14159265358979; };
  const auto weight = [&](std::uint32_t x, std::uint32_t y) { return r.orientation.at(x, y, 1); };
  const double horizontal = angle_deg(100, 89);  // the horizontal strand's centre line
  CHECK(std::min(horizontal, 180 - horizontal) < 0.5);
  CHECK(weight(100, 89) == doctest::Approx(1.0).epsilon(1e-3));
  CHECK(angle_deg(110, 110) == doctest::Approx(45.0).epsilon(0.01));  // the diagonal one
  CHECK(weight(110, 110) == doctest::Approx(1.0).epsilon(1e-3));
  CHECK(weight(100, 150) == 0.0f);  // background
  // At the strand's edge (row 85, half covered) only some samples see it: the weight is that share.
  const float edge = weight(100, 85);
  CHECK(edge > 0.0f);
  CHECK(edge < 1.0f);
  CHECK(edge == doctest::Approx(r.coverage.at(100, 85, 0)).epsilon(1e-4));
}

TEST_CASE("a written synthetic scene: files, ground truth, and roots inside the masks through every camera reader") {
  const fs::path root = fs::temp_directory_path() / "nf_synth_test";
  fs::remove_all(root);
  fs::create_directories(root);
  const fs::path out = root / "cat";
  synth::SynthOptions o;
  o.animal = "cat", o.views = 6, o.resolution = 192, o.seed = 5, o.strands = 50000, o.samples_per_axis = 2;
  o.body_voxel = 0.004f;

  SUBCASE("a folder that is not a synth scene is never touched") {
    fs::create_directories(out);
    std::ofstream(out / "my_notes.txt") << "mine";
    CHECK_THROWS_WITH_AS(synth::synthesize_scene(out, o), doctest::Contains("is not an nf_gpu synth scene"), UsageError);
    CHECK(fs::exists(out / "my_notes.txt"));
    CHECK(!fs::exists(out / "transforms.json"));
  }

  SUBCASE("outputs") {
    const json info = synth::synthesize_scene(out, o);
    for (const char* f : {"transforms.json", "gt/strands.hair", "gt/bald.ply", "gt/outer.ply", "gt/knowledge.json",
                          "gt/scene.json", "gt/body.glb", "images/000.png", "masks/005.png"})
      CHECK(fs::exists(out / f));
    CHECK(!fs::exists(root / "cat.partial"));
    CHECK_THROWS_WITH_AS(synth::synthesize_scene(out, o), doctest::Contains("--overwrite"), UsageError);

    const io::Scene scene = io::read_scene(out);
    REQUIRE(scene.cameras.size() == 6);
    CHECK_NOTHROW(scene.check_files("transforms.json"));
    CHECK(scene.cm_per_unit.value() == 100.0);
    const io::StrandSet strands = io::read_hair(out / "gt" / "strands.hair");
    CHECK(strands.strand_count() == 50000);
    CHECK(strands.points_in(0) == 100);
    const geometry::Mesh bald = io::read_mesh(out / "gt" / "bald.ply");
    CHECK(bald.regions.size() == bald.vertex_count());
    CHECK(io::read_mesh(out / "gt" / "body.glb").vertex_count() == bald.vertex_count());
    const geometry::Mesh outer = io::read_mesh(out / "gt" / "outer.ply");
    CHECK(geometry::is_closed_manifold(outer));
    const knowledge::Knowledge k = knowledge::read_knowledge(out / "gt" / "knowledge.json");
    const glm::vec3 left(info["eye_centres"]["left"][0], info["eye_centres"]["left"][1], info["eye_centres"]["left"][2]);
    const glm::vec3 right(info["eye_centres"]["right"][0], info["eye_centres"]["right"][1], info["eye_centres"]["right"][2]);
    CHECK(k.eye_distance_cm == doctest::Approx(100 * glm::distance(left, right)).epsilon(1e-4));
    // The truth's version: a cached scene made by an earlier synth with a wrong truth is not current.
    CHECK(info["truth_version"] == synth::kTruthVersion);
    CHECK(synth::truth_is_current(out));
    json older = info;
    older.erase("truth_version");
    std::ofstream(out / "gt" / "scene.json") << older.dump(2);
    CHECK(!synth::truth_is_current(out));
    CHECK(!synth::truth_is_current(root / "nothing here"));
    std::ofstream(out / "gt" / "scene.json") << info.dump(2);

    // Each region's thickness is the grown fur's: the median distance from the region's body
    // vertices to the envelope. Checked independently through the envelope's nearest vertex, which
    // is at most about a voxel further than its nearest face.
    {
      const geometry::PointIndex outer_vertices(outer.positions);
      const float voxel = info["outer"]["voxel"].get<float>();
      int checked = 0;
      for (int r = 0; r < body::kRegionCount; ++r) {
        const auto region = static_cast<body::Region>(r);
        if (!k.grows_fur(region)) continue;
        std::vector<double> gap;
        for (std::size_t v = 0; v < bald.vertex_count(); ++v)
          if (bald.regions[v] == r) gap.push_back(std::sqrt(outer_vertices.nearest(&bald.positions[3 * v]).second));
        if (gap.size() < 50) continue;
        const float thickness = k.at(region).thickness_cm / 100.0f;
        CAPTURE(body::kRegionNames[std::size_t(r)]);
        CHECK(thickness > 0);
        CHECK(thickness <= k.at(region).length_cm / 100.0f);
        // (capped at the length: a paw pad's 1 mm fur sits in an envelope closed over the toes)
        const float expected = std::min(float(median(std::move(gap))), k.at(region).length_cm / 100.0f);
        CHECK(thickness <= expected + 1e-5f);
        CHECK(thickness >= expected - voxel);
        ++checked;
      }
      CHECK(checked >= 8);
      // The preset's rule (0.35 x length) is not what this fur has: the body's fur stands higher.
      CHECK(k.at(body::Region::body).thickness_cm > 0.4f * k.at(body::Region::body).length_cm);
    }

    // The envelope holds the fur: strand tips lie within the closing radius (plus a voxel) of it or inside.
    std::vector<glm::vec3> roots;
    for (std::uint32_t s = 0; s < strands.strand_count(); ++s) roots.push_back(at(strands.points, strands.offsets[s]));
    const geometry::PointIndex outer_index(outer.positions);
    const float slack = info["outer"]["closing_radius"].get<float>() + 2 * info["outer"]["voxel"].get<float>();
    int outside = 0;
    for (std::uint32_t s = 0; s < strands.strand_count(); ++s) {
      const std::uint32_t tip = strands.offsets[s + 1] - 1;
      const auto [i, d2] = outer_index.nearest(&strands.points[3 * tip]);
      const glm::vec3 q = at(strands.points, tip);
      outside += glm::dot(q - at(outer.positions, i), at(outer.normals, i)) > slack;
    }
    CHECK(outside < int(strands.strand_count() / 100));

    // Roots project into the masks through transforms.json ...
    CHECK(fraction_in_masks(scene, roots) >= 0.99);
    // ... and through NeuS, Artemis and COLMAP files written from the same cameras.
    const fs::path neus = root / "neus", artemis = root / "artemis", colmap = root / "colmap";
    fs::create_directories(neus / "image");
    fs::create_directories(neus / "mask");
    fs::create_directories(artemis);
    fs::create_directories(colmap / "masks");
    test::write_neus_cameras(neus, scene.cameras);
    test::write_artemis_cameras(artemis, scene.cameras);
    test::write_colmap_cameras(colmap, scene.cameras);
    for (std::size_t i = 0; i < scene.cameras.size(); ++i) {
      const io::Camera& c = scene.cameras[i];
      fs::copy_file(c.image, neus / "image" / (c.name + ".png"));
      fs::copy_file(c.mask, neus / "mask" / (c.name + ".png"));
      test::write_jpeg_header(artemis / (test::artemis_name(i) + ".jpg"), c.width, c.height);
      fs::copy_file(c.mask, artemis / (test::artemis_name(i) + "_alpha.png"));
      fs::copy_file(c.mask, colmap / "masks" / (c.name + ".png"));
    }
    for (const fs::path& folder : {neus, artemis, colmap}) {
      CAPTURE(folder);
      const io::Scene other = io::read_scene(folder);
      REQUIRE(other.cameras.size() == scene.cameras.size());
      CHECK(fraction_in_masks(other, roots) >= 0.99);
    }
    // The check can fail: a classic mistake (world-to-camera rotation used as camera-to-world)
    // sends the roots out of the masks.
    io::Scene wrong = scene;
    for (auto& c : wrong.cameras) {
      const glm::dmat3 r = glm::transpose(glm::dmat3(c.camera_to_world));
      for (int col = 0; col < 3; ++col) c.camera_to_world[col] = glm::dvec4(r[col], 0.0);
    }
    CHECK(fraction_in_masks(wrong, roots) < 0.5);

    // Overwriting an earlier synth scene is allowed when asked, however the folder is spelled.
    o.overwrite = true, o.views = 2;
    synth::synthesize_scene(out.string() + "/", o);
    CHECK(io::read_scene(out).cameras.size() == 2);
    CHECK(!fs::exists(out / ".partial"));
  }
  fs::remove_all(root);
}

TEST_CASE("the photos' look: shading models, hair width and sensor noise change what they should and nothing else") {
  io::Camera cam;
  cam.name = "front";
  cam.width = cam.height = 120;
  cam.fx = cam.fy = 300, cam.cx = cam.cy = 60;
  cam.camera_to_world = glm::translate(glm::dmat4(1.0), glm::dvec3(0, 0, 2));
  // A fan of strands in the image plane at every angle: every model's highlight shows somewhere.
  std::vector<float> xyz;
  const std::uint32_t strands = 24;
  for (std::uint32_t s = 0; s < strands; ++s) {
    const float a = 3.14159265f * float(s) / strands;
    for (int k = 0; k < 50; ++k) {
      const float t = 0.02f + 0.3f * float(k) / 49.f;
      xyz.insert(xyz.end(), {t * std::cos(a), t * std::sin(a), 0.1f * t});
    }
  }
  const io::StrandSet fan = io::StrandSet::uniform(strands, 50, xyz);
  synth::StrandLook look;
  look.radius = 0.004f;
  look.root_colors.assign(strands, glm::vec3(0.6f, 0.3f, 0.1f));
  const auto render = [&](synth::HairShading shading, float width) {
    synth::RenderOptions o;
    o.samples_per_axis = 2, o.shading = shading;
    synth::StrandLook l = look;
    l.radius *= width;
    return synth::StrandRenderer(geometry::Mesh{}, {}, fan, l, o).render(cam);
  };
  const synth::Rendered kk = render(synth::HairShading::KajiyaKay, 1), two = render(synth::HairShading::TwoLobe, 1),
                        matte = render(synth::HairShading::Matte, 1), wide = render(synth::HairShading::KajiyaKay, 2);
  const auto sum = [](const io::Image& i) {
    double s = 0;
    for (float v : i.pixels) s += v;
    return s;
  };
  // The shading changes the colours, not where the strands are.
  CHECK(sum(two.coverage) == doctest::Approx(sum(kk.coverage)));
  CHECK(sum(matte.coverage) == doctest::Approx(sum(kk.coverage)));
  double differ = 0, brightest_kk = 0, brightest_matte = 0;
  for (std::size_t p = 0; p < kk.rgb.pixels.size(); ++p) {
    differ += std::abs(kk.rgb.pixels[p] - two.rgb.pixels[p]);
    brightest_kk = std::max(brightest_kk, double(kk.rgb.pixels[p]));
    brightest_matte = std::max(brightest_matte, double(matte.rgb.pixels[p]));
  }
  CHECK(differ / sum(kk.coverage) > 0.02);  // per covered pixel and channel
  CHECK(brightest_kk > brightest_matte);     // the highlight outshines matte's slightly stronger diffuse term
  // Twice the width covers about twice the pixels.
  CHECK(sum(wide.coverage) == doctest::Approx(2 * sum(kk.coverage)).epsilon(0.15));
  CHECK_THROWS_AS(synth::hair_shading_from("phong"), UsageError);
  CHECK(synth::hair_shading_from("two-lobe") == synth::HairShading::TwoLobe);

  // Sensor noise: the same scene with noise of 6 levels differs from the clean one by about that,
  // and the masks, the cameras and the truth do not change.
  const fs::path root = fs::temp_directory_path() / "nf_synth_look_test";
  fs::remove_all(root);
  synth::SynthOptions o;
  o.animal = "cat", o.views = 1, o.resolution = 64, o.seed = 2, o.strands = 3000, o.samples_per_axis = 1, o.body_voxel = 0.01f;
  synth::synthesize_scene(root / "clean", o);
  o.photo_noise = 6;
  const json info = synth::synthesize_scene(root / "noisy", o);
  CHECK(info["render"]["photo_noise"].get<double>() == 6.0);
  const io::Image a = io::read_image(root / "clean" / "images" / "000.png"), b = io::read_image(root / "noisy" / "images" / "000.png");
  REQUIRE(a.pixels.size() == b.pixels.size());
  double sq = 0;
  std::size_t n = 0;
  for (std::size_t p = 0; p < a.pixels.size(); ++p)
    if (a.pixels[p] > 0.05f && a.pixels[p] < 0.95f) sq += double(a.pixels[p] - b.pixels[p]) * (a.pixels[p] - b.pixels[p]), ++n;
  REQUIRE(n > 100);
  CHECK(std::sqrt(sq / double(n)) * 255 == doctest::Approx(6.0).epsilon(0.15));
  CHECK(io::read_image(root / "clean" / "masks" / "000.png").pixels == io::read_image(root / "noisy" / "masks" / "000.png").pixels);
  o.photo_noise = -1;
  CHECK_THROWS_AS(synth::synthesize_scene(root / "bad", o), UsageError);

  fs::remove_all(root);
}

TEST_CASE("a coat drawn wider than the preset: each region's fur length within the spread, the truth saying what grew") {
  const fs::path root = fs::temp_directory_path() / "nf_synth_spread_test";
  fs::remove_all(root);
  synth::SynthOptions o;
  o.animal = "cat", o.views = 1, o.resolution = 64, o.seed = 2, o.strands = 3000, o.samples_per_axis = 1, o.body_voxel = 0.01f;
  o.fur_length_spread = 0.4f, o.proportion_spread = 0.2f;
  const json spread = synth::synthesize_scene(root / "spread", o);
  CHECK(spread["strands"]["length_spread"].get<double>() == 0.4);
  CHECK(spread["body"]["proportion_spread"].get<double>() == 0.2);
  // The strands grew at the lengths the truth states: per region, their mean length against the
  // preset's follows the truth's factor (the coat's own jitter, curl and clumping averaging out).
  const knowledge::Knowledge preset = knowledge::preset("cat"), grown = knowledge::read_knowledge(root / "spread" / "gt" / "knowledge.json");
  const io::StrandSet strands = io::read_hair(root / "spread" / "gt" / "strands.hair");
  const geometry::Mesh bald = io::read_mesh(root / "spread" / "gt" / "bald.ply");  // a region per vertex: the root's
  const geometry::PointIndex bald_index(bald.positions);
  std::vector<double> length_sum(preset.regions.size(), 0.0);
  std::vector<std::size_t> count(preset.regions.size(), 0);
  for (std::uint32_t i = 0; i < strands.strand_count(); ++i) {
    const float* p = strands.points.data() + 3 * std::size_t(strands.offsets[i]);
    const std::size_t region = std::size_t(bald.regions[bald_index.nearest(p).first]);
    double length = 0;
    for (std::uint32_t k = 1; k < strands.points_in(i); ++k)
      length += glm::length(glm::vec3(p[3 * k], p[3 * k + 1], p[3 * k + 2]) - glm::vec3(p[3 * k - 3], p[3 * k - 2], p[3 * k - 1]));
    length_sum[region] += length * 100.0;  // cm: synth writes metres
    ++count[region];
  }
  double widest = 0;
  std::size_t compared = 0, refuted = 0;
  for (std::size_t r = 0; r < preset.regions.size(); ++r) {
    if (!preset.regions[r] || preset.regions[r]->length_cm <= 0) continue;
    REQUIRE(grown.regions[r]);
    const double f = grown.regions[r]->length_cm / preset.regions[r]->length_cm;
    CHECK(f >= 0.6 - 1e-4);
    CHECK(f <= 1.4 + 1e-4);
    widest = std::max(widest, std::abs(f - 1));
    if (count[r] < 100) continue;
    INFO("region ", body::region_name(std::int32_t(r)));
    const double mean = length_sum[r] / double(count[r]);
    CHECK(mean == doctest::Approx(grown.regions[r]->length_cm).epsilon(0.15));
    // Where the spread moved a region by more than the tolerance, the preset's length is refuted.
    if (std::abs(f - 1) > 0.25) {
      CHECK(std::abs(mean / preset.regions[r]->length_cm - 1) > 0.15);
      ++refuted;
    }
    ++compared;
  }
  CHECK(widest > 0.1);
  CHECK(compared >= 3);
  CHECK(refuted >= 1);
  o.fur_length_spread = 0.95f;
  CHECK_THROWS_WITH_AS(synth::synthesize_scene(root / "bad", o), doctest::Contains("--fur-length-spread"), UsageError);
  o.fur_length_spread = 0, o.proportion_spread = 0.6f;
  CHECK_THROWS_WITH_AS(synth::synthesize_scene(root / "bad", o), doctest::Contains("--proportion-spread"), UsageError);
  CHECK_FALSE(fs::exists(root / "bad"));
  fs::remove_all(root);
}

TEST_CASE("a person's photos: a hand-held path that still frames the animal, JPEGs with EXIF, shaken views") {
  // The rig and the hand-held path around the same sphere: every hand-held view still holds the
  // sphere's centre well inside its frame, and no two hand-held steps are alike as the rig's are.
  synth::RigOptions rig;
  rig.views = 24, rig.width = rig.height = 200;
  const std::vector<io::Camera> rings = synth::camera_rings({0, 0.3f, 0}, 0.5f, {0, 1, 0}, rig);
  rig.handheld = true;
  const std::vector<io::Camera> walk = synth::camera_rings({0, 0.3f, 0}, 0.5f, {0, 1, 0}, rig);
  REQUIRE(walk.size() == rings.size());
  double largest_roll = 0, step_spread = 0;
  for (std::size_t i = 0; i < walk.size(); ++i) {
    const glm::dvec3 p = walk[i].project({0, 0.3, 0});
    CHECK(p.z > 0);
    CHECK(std::abs(p.x - 100) < 30);
    CHECK(std::abs(p.y - 100) < 30);
    // Roll: the camera's x axis leaves the horizontal plane.
    largest_roll = std::max(largest_roll, std::abs(std::asin(glm::dvec3(walk[i].camera_to_world[0]).y)) * 180 / M_PI);
    if (i > 0 && i < 12)
      step_spread = std::max(step_spread, std::abs(glm::distance(walk[i].centre(), walk[i - 1].centre()) - glm::distance(rings[i].centre(), rings[i - 1].centre())));
  }
  CHECK(largest_roll > 1.0);
  CHECK(largest_roll <= 5.0 + 1e-9);
  CHECK(step_spread > 0.05 * glm::distance(rings[1].centre(), rings[0].centre()));

  // JPEG photos with a camera's EXIF, two of six views shaken: the shaken ones are the blurrier.
  const fs::path root = fs::temp_directory_path() / "nf_synth_person_test";
  fs::remove_all(root);
  synth::SynthOptions o;
  o.animal = "dog", o.views = 6, o.resolution = 96, o.strands = 3000, o.samples_per_axis = 1, o.body_voxel = 0.01f;
  o.backdrop = "textured", o.photo_format = "jpeg", o.camera_path = "handheld", o.blurred_views = 2;
  const json info = synth::synthesize_scene(root, o);
  CHECK(info["render"]["photo_format"] == "jpeg");
  const io::Scene scene = io::read_scene(root);
  REQUIRE(scene.cameras.size() == 6);
  std::vector<double> detail;
  for (const io::Camera& c : scene.cameras) {
    CHECK(c.image.extension() == ".jpg");
    std::ifstream in(c.image, std::ios::binary);
    std::string head(64, '\0');
    in.read(head.data(), 64);
    CHECK(head.find(std::string("Exif\0\0", 6)) != std::string::npos);
    const io::Image photo = io::read_image(c.image);
    double sum = 0;  // horizontal detail: what a sideways shake removes
    for (std::uint32_t y = 0; y < photo.height; ++y)
      for (std::uint32_t x = 1; x < photo.width; ++x) sum += std::abs(photo.at(x, y, 1) - photo.at(x - 1, y, 1));
    detail.push_back(sum);
  }
  // Views 1 and 4 (the middle of each run of three) are shaken.
  for (const std::size_t shaken : {1, 4})
    for (const std::size_t sharp : {0, 2, 3, 5}) CHECK(detail[shaken] < 0.8 * detail[sharp]);
  o.camera_path = "drone";
  CHECK_THROWS_AS(synth::synthesize_scene(root / "bad", o), UsageError);
  fs::remove_all(root);
}
