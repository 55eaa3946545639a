// Strand files: every format round-trips (with its optional arrays, colours included where the
// format holds them, empty and single-strand sets),
// and malformed files give errors that name the file and the field.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "engine/core/color.hpp"
#include "engine/core/error.hpp"
#include "tests/support/files.hpp"
#include "engine/io/strand_files.hpp"

using namespace nf;
using namespace nf::io;
namespace fs = std::filesystem;
using nf::test::slurp;
using nf::test::spit;

namespace {

fs::path temp(const std::string& name) { return fs::temp_directory_path() / ("nf_test_" + name); }

StrandSet sample() {
  StrandSet s;
  s.offsets = {0, 1, 3, 8};  // strands of 1, 2 and 5 points
  for (int p = 0; p < 8; ++p) {
    s.points.insert(s.points.end(), {0.1f * p, -0.25f * p, 1e-3f * p * p});
    s.thickness.push_back(0.01f + 0.001f * p);
    s.transparency.push_back(0.1f * p);
    s.colors.insert(s.colors.end(), {0.5f, 0.25f, 0.125f * p});
  }
  s.regions = {3, 0, 15};
  return s;
}

}  // namespace

TEST_CASE("every strand format round-trips what it can hold") {
  const StrandSet s = sample();
  for (const char* ext : {".hair", ".ply", ".obj", ".usda"}) {
    CAPTURE(ext);
    const fs::path path = temp(std::string("strands") + ext);
    write_strands(path, s);
    const StrandSet r = read_strands(path);
    CHECK(r.offsets == s.offsets);
    CHECK(r.points == s.points);
    const std::string e = ext;
    if (e == ".hair") {
      CHECK(r.thickness == s.thickness);
      CHECK(r.transparency == s.transparency);
      CHECK(r.colors == s.colors);
      CHECK(r.regions.empty());  // .hair has no region field
    }
    if (e == ".ply" || e == ".usda") {
      CHECK(r.thickness == s.thickness);
      CHECK(r.regions == s.regions);
      // Colours: PLY's as 8-bit sRGB (half a step off at most), USD's displayColor as written.
      REQUIRE(r.colors.size() == s.colors.size());
      for (std::size_t i = 0; i < s.colors.size(); ++i) {
        if (e == ".usda") CHECK(r.colors[i] == doctest::Approx(s.colors[i]).epsilon(1e-6));
        else CHECK(std::abs(color::linear_to_srgb(r.colors[i]) - color::linear_to_srgb(s.colors[i])) <= 0.5f / 255.f + 1e-5f);
      }
    }
    if (e == ".obj") CHECK(r.colors.empty());  // OBJ lines carry no colour
    fs::remove(path);
  }
}

TEST_CASE("a USD groom's constant displayColor (another tool's) is left out, not refused") {
  const fs::path path = temp("strands_constant_color.usda");
  write_strands(path, sample());
  std::string text = slurp(path);
  const std::size_t at = text.find("color3f[] primvars:displayColor = [");
  REQUIRE(at != std::string::npos);
  const std::size_t end = text.find(']', at);
  text.replace(at, end - at + 1, "color3f[] primvars:displayColor = [(0.5, 0.4, 0.3)]");
  spit(path, text);
  const StrandSet r = read_strands(path);
  CHECK(r.points == sample().points);
  CHECK(r.colors.empty());
  fs::remove(path);
}

TEST_CASE("empty sets, a single point and engine-layout strands round-trip") {
  StrandSet empty;
  StrandSet single;
  single.offsets = {0, 1};
  single.points = {1.f, 2.f, 3.f};
  std::vector<float> xyz(50 * 100 * 3);
  for (std::size_t i = 0; i < xyz.size(); ++i) xyz[i] = float(i % 977) * 1e-3f;
  const StrandSet engine = StrandSet::uniform(50, 100, xyz);
  for (const char* ext : {".hair", ".ply", ".obj", ".usda"}) {
    CAPTURE(ext);
    const fs::path path = temp(std::string("strands_small") + ext);
    for (const StrandSet* s : {static_cast<const StrandSet*>(&empty), static_cast<const StrandSet*>(&single), &engine}) {
      write_strands(path, *s);
      const StrandSet r = read_strands(path);
      CHECK(r.strand_count() == s->strand_count());
      CHECK(r.points == s->points);
    }
    fs::remove(path);
  }
}

TEST_CASE("malformed .hair files name the file and the field") {
  const fs::path path = temp("bad.hair");
  write_hair(path, sample());
  const std::string good = slurp(path);

  spit(path, "HAIX" + good.substr(4));
  CHECK_THROWS_WITH_AS(read_hair(path), doctest::Contains("signature"), InputError);
  spit(path, good.substr(0, good.size() - 7));
  CHECK_THROWS_WITH_AS(read_hair(path), doctest::Contains("truncated"), InputError);
  spit(path, good.substr(0, 60));
  CHECK_THROWS_WITH_AS(read_hair(path), doctest::Contains("header"), InputError);
  std::string huge = good;
  const std::uint32_t many = 4000000000u;
  std::memcpy(&huge[8], &many, 4);  // point count far beyond the file
  spit(path, huge);
  CHECK_THROWS_WITH_AS(read_hair(path), doctest::Contains("header counts"), InputError);
  std::string mismatch = good;
  const std::uint32_t seven = 7;
  std::memcpy(&mismatch[8], &seven, 4);  // 8 points stored, header says 7
  spit(path, mismatch);
  CHECK_THROWS_AS(read_hair(path), InputError);
  std::string nan = good;
  const float bad = NAN;
  std::memcpy(&nan[128 + 3 * 2 + 4], &bad, 4);  // a coordinate of the first point
  spit(path, nan);
  CHECK_THROWS_WITH_AS(read_hair(path), doctest::Contains("points: element 1"), InputError);
  spit(path, good + "xx");
  CHECK_THROWS_WITH_AS(read_hair(path), doctest::Contains("follow the last array"), InputError);
  fs::remove(path);
  CHECK_THROWS_WITH_AS(read_hair(path), doctest::Contains("cannot open"), InputError);
}

TEST_CASE("malformed PLY, OBJ and USDA strand files are rejected with the problem named") {
  const fs::path ply = temp("bad.ply"), obj = temp("bad.obj"), usda = temp("bad.usda");
  write_strands_ply(ply, sample());
  const std::string good_ply = slurp(ply);
  spit(ply, good_ply.substr(0, good_ply.size() - 5));
  CHECK_THROWS_AS(read_strands_ply(ply), InputError);
  spit(ply, "ply\nformat ascii 1.0\nend_header\n");
  CHECK_THROWS_WITH_AS(read_strands_ply(ply), doctest::Contains("binary little-endian"), InputError);

  spit(obj, "v 0 0 0\nv 1 1 1\nl 1 3\n");
  CHECK_THROWS_WITH_AS(read_strands_obj(obj), doctest::Contains("line 3: vertex index 3"), InputError);
  spit(obj, "v 0 0\n");
  CHECK_THROWS_WITH_AS(read_strands_obj(obj), doctest::Contains("line 1"), InputError);
  spit(obj, "v 0 0 0\nv 1 1 1\nl -2 -1\n");  // negative indices count back
  CHECK(read_strands_obj(obj).point_count() == 2);

  spit(usda, "#usda 1.0\ndef BasisCurves \"fur\" { int[] curveVertexCounts = [2] point3f[] points = [(0, 0, 0)] }\n");
  CHECK_THROWS_WITH_AS(read_strands_usda(usda), doctest::Contains("cover 2 points but 1"), InputError);
  spit(usda, "#usda 1.0\ndef BasisCurves \"fur\" { int[] curveVertexCounts = [x] }\n");
  CHECK_THROWS_WITH_AS(read_strands_usda(usda), doctest::Contains("not a number"), InputError);
  for (const auto& p : {ply, obj, usda}) fs::remove(p);
}

TEST_CASE("writing never leaves a partial file and never replaces a good one with a bad set") {
  const fs::path path = temp("keep.hair");
  write_hair(path, sample());
  const std::string before = slurp(path);
  StrandSet broken = sample();
  broken.points[4] = INFINITY;
  CHECK_THROWS_WITH_AS(write_hair(path, broken), doctest::Contains("points: element 4"), InputError);
  CHECK(slurp(path) == before);
  CHECK_THROWS_WITH_AS(write_strands(temp("x.abc"), sample()), doctest::Contains("unknown strand format"), InputError);
  fs::remove(path);
}
