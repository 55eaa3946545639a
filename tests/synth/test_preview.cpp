// `nf_gpu render` previews: PNGs per view at the camera's size, strands in the palette colour of
// their region (from the nearest body vertex, or from the strand file), bad inputs named.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include <unistd.h>

#include "engine/core/error.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/io/image.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/scene.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/synth/preview.hpp"
#include "engine/synth/synth_scene.hpp"

using namespace nf;
namespace fs = std::filesystem;

namespace {

float to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

glm::vec3 chroma(glm::vec3 linear) { return linear / (linear.r + linear.g + linear.b); }

// Pixels whose linear chromaticity lies within `tol` of the palette colour of `region`.
std::size_t pixels_of_region(const io::Image& img, std::int32_t region, float tol = 0.02f) {
  const glm::vec3 srgb = synth::region_palette()[std::size_t(region)];
  const glm::vec3 target = chroma({to_linear(srgb.r), to_linear(srgb.g), to_linear(srgb.b)});
  std::size_t n = 0;
  for (std::uint32_t y = 0; y < img.height; ++y)
    for (std::uint32_t x = 0; x < img.width; ++x) {
      const glm::vec3 c(to_linear(img.at(x, y, 0)), to_linear(img.at(x, y, 1)), to_linear(img.at(x, y, 2)));
      if (c.r + c.g + c.b < 0.1f) continue;  // background and deep shadow
      n += glm::length(chroma(c) - target) < tol;
    }
  return n;
}

struct TempScene {
  fs::path root;
  TempScene() {
    root = fs::temp_directory_path() / ("nf_test_preview_" + std::to_string(::getpid()));
    fs::remove_all(root);
    fs::create_directories(root);
    synth::SynthOptions o;
    o.animal = "cat";
    o.views = 2, o.resolution = 64, o.strands = 2000, o.body_voxel = 0.006f, o.samples_per_axis = 1;
    synth::synthesize_scene(root / "scene", o);
  }
  ~TempScene() { fs::remove_all(root); }
  fs::path scene() const { return root / "scene"; }
  fs::path strands() const { return root / "scene" / "gt" / "strands.hair"; }
  fs::path mesh() const { return root / "scene" / "gt" / "bald.ply"; }
};

const TempScene& fixture() {
  static const TempScene scene;
  return scene;
}

}  // namespace

TEST_CASE("previews: one PNG per view at the camera's size, strands in their region's palette colour") {
  const TempScene& t = fixture();
  const io::Scene scene = io::read_scene(t.scene());
  REQUIRE(scene.cameras.size() == 2);
  const fs::path out = t.root / "previews";
  fs::create_directories(out);
  std::ofstream(out / "notes.txt") << "not a preview";

  synth::PreviewOptions o;
  o.strands = t.strands(), o.mesh = t.mesh(), o.scene = t.scene(), o.out = out;
  o.samples_per_axis = 2;
  const auto r = synth::render_previews(o);
  CHECK(r.coloring == "nearest body vertex region");
  CHECK(r.strand_radius > 0);
  REQUIRE(r.files.size() == 2);
  CHECK(std::ifstream(out / "notes.txt").good());  // nothing else in the folder is touched

  // The regions the strands take: those of the body vertices nearest to their roots.
  const geometry::Mesh mesh = io::read_mesh(t.mesh());
  const io::StrandSet strands = io::read_strands(t.strands());
  const geometry::PointIndex index(mesh.positions);
  std::set<std::int32_t> present;
  for (std::uint32_t s = 0; s < strands.strand_count(); ++s)
    present.insert(mesh.regions[index.nearest(&strands.points[3 * std::size_t(strands.offsets[s])]).first]);
  REQUIRE(!present.empty());

  std::size_t matched = 0;
  for (std::size_t v = 0; v < 2; ++v) {
    const fs::path expected = out / (scene.cameras[v].name + ".png");
    CHECK(r.files[v] == expected);
    REQUIRE(fs::exists(expected));
    const io::Image img = io::read_image(expected);
    CHECK(img.width == scene.cameras[v].width);
    CHECK(img.height == scene.cameras[v].height);
    CHECK(img.channels >= 3);
    for (std::int32_t region : present) matched += pixels_of_region(img, region);
  }
  CHECK(matched >= 10);

  // Wider strands: the radius scales; a single view renders one file.
  o.width_scale = 2.0, o.views = "1";
  const auto wide = synth::render_previews(o);
  CHECK(wide.strand_radius == doctest::Approx(2 * r.strand_radius));
  CHECK(wide.files.size() == 1);
}

TEST_CASE("previews: per-strand regions from the strand file win over the body's") {
  const TempScene& t = fixture();
  io::StrandSet strands = io::read_strands(t.strands());
  strands.regions.assign(strands.strand_count(), std::uint16_t(body::Region::face));
  const fs::path file = t.root / "face_strands.ply";
  io::write_strands(file, strands);
  synth::PreviewOptions o;
  o.strands = file, o.mesh = t.mesh(), o.scene = t.scene(), o.out = t.root / "face_previews";
  o.views = "0";
  const auto r = synth::render_previews(o);
  CHECK(r.coloring == "strand regions");
  REQUIRE(r.files.size() == 1);
  const io::Image img = io::read_image(r.files[0]);
  CHECK(pixels_of_region(img, std::int32_t(body::Region::face)) >= 10);
  CHECK(pixels_of_region(img, std::int32_t(body::Region::leg_front)) == 0);
}

TEST_CASE("previews: bad inputs are refused with the file or field named") {
  const TempScene& t = fixture();
  synth::PreviewOptions o;
  o.strands = t.root / "missing.hair", o.mesh = t.mesh(), o.scene = t.scene(), o.out = t.root / "bad";
  CHECK_THROWS_WITH_AS(synth::render_previews(o), doctest::Contains("missing.hair"), InputError);
  o.strands = t.strands(), o.mesh = t.root / "missing.ply";
  CHECK_THROWS_WITH_AS(synth::render_previews(o), doctest::Contains("missing.ply"), InputError);
  o.mesh = t.mesh(), o.scene = t.root / "no_scene";
  CHECK_THROWS_WITH_AS(synth::render_previews(o), doctest::Contains("no_scene"), InputError);
  o.scene = t.scene(), o.views = "0,5";
  CHECK_THROWS_WITH_AS(synth::render_previews(o), doctest::Contains("--views: camera index 5 is out of range"),
                       UsageError);
  o.views = "0,x";
  CHECK_THROWS_WITH_AS(synth::render_previews(o), doctest::Contains("--views"), UsageError);
  o.views = "all", o.width_scale = 0;
  CHECK_THROWS_WITH_AS(synth::render_previews(o), doctest::Contains("--width-scale"), UsageError);
  CHECK(!fs::exists(t.root / "bad"));  // nothing written on a refused run

  CHECK(io::parse_view_list("all", 3) == std::vector<std::uint32_t>{0, 1, 2});
  CHECK(io::parse_view_list("2, 0,2", 3) == std::vector<std::uint32_t>{2, 0});
  CHECK_THROWS_AS(io::parse_view_list("", 3), UsageError);
  CHECK_THROWS_AS(io::parse_view_list("1,", 3), UsageError);
}
