// Streamed groom writers: a groom handed over in chunks of any size writes the same files the
// in-memory writers do, every format reads back with its points, widths and regions; a .hair file
// streams back chunk by chunk; a .usda groom with its body holds prims whose arrays have the
// lengths USD requires (no USD library here: a structural check); the rigged glTF round-trips its
// skeleton.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <sstream>

#include "engine/core/error.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/io/strand_stream.hpp"

using namespace nf;
using namespace nf::io;
namespace fs = std::filesystem;

namespace {

fs::path temp(const std::string& name) { return fs::temp_directory_path() / ("nf_test_stream_" + name); }

// Strands of varying point counts, regions and widths.
StrandSet groom(std::uint32_t strands, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  StrandSet s;
  s.offsets.push_back(0);
  for (std::uint32_t i = 0; i < strands; ++i) {
    const std::uint32_t n = 2 + i % 7;
    for (std::uint32_t k = 0; k < n; ++k) {
      s.points.insert(s.points.end(), {u(rng), u(rng), u(rng)});
      s.thickness.push_back(0.001f * float(1 + k));
    }
    s.offsets.push_back(s.offsets.back() + n);
    s.regions.push_back(std::uint16_t(i % 16));
  }
  return s;
}

// The same set handed over in chunks of `chunk` points.
StrandStream chunked(const StrandSet& s, std::size_t chunk) {
  StrandStream stream = StrandStream::of(s);
  stream.each_chunk = [&s, chunk](const PointSink& sink) {
    for (std::size_t p = 0; p < s.point_count(); p += chunk)
      sink(std::span<const float>(s.points).subspan(3 * p, 3 * std::min(chunk, std::size_t(s.point_count() - p))));
  };
  return stream;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Number of values in the `[...]` array of the attribute named `name` inside `prim` text.
std::size_t array_length(const std::string& prim, const std::string& name, int per_value) {
  const std::size_t at = prim.find(name + " = [");
  REQUIRE_MESSAGE(at != std::string::npos, name);
  const std::size_t open = prim.find(" = [", at) + 3, close = prim.find(']', open);
  std::size_t numbers = 0;
  bool in_number = false;
  for (std::size_t i = open + 1; i < close; ++i) {
    const char c = prim[i];
    const bool part = std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '.' || c == 'e' || c == '+';
    if (part && !in_number) ++numbers;
    in_number = part;
  }
  CHECK_MESSAGE(numbers % std::size_t(per_value) == 0, name);
  return numbers / std::size_t(per_value);
}

}  // namespace

TEST_CASE("streamed writers match the in-memory ones and read back, whatever the chunk size") {
  const StrandSet s = groom(40, 1);
  for (const char* ext : {".hair", ".ply", ".obj", ".usda"}) {
    CAPTURE(ext);
    const fs::path whole = temp(std::string("whole") + ext);
    if (std::string(ext) == ".hair") {
      StrandSet plain = s;  // the stream carries widths and regions only
      write_hair(whole, StrandStream::of(plain));
    } else {
      write_strands(whole, s);
    }
    for (std::size_t chunk : {1u, 7u, 64u, 100000u}) {
      CAPTURE(chunk);
      const fs::path part = temp(std::string("chunked") + ext);
      const StrandStream stream = chunked(s, chunk);
      if (std::string(ext) == ".hair") write_hair(part, stream);
      else if (std::string(ext) == ".ply") write_strands_ply(part, stream);
      else if (std::string(ext) == ".obj") write_strands_obj(part, stream);
      else write_strands_usda(part, stream);
      CHECK(slurp(part) == slurp(whole));
      const StrandSet r = read_strands(part);
      CHECK(r.offsets == s.offsets);
      CHECK(r.points == s.points);
      if (std::string(ext) != ".obj") CHECK(r.thickness == s.thickness);
      if (std::string(ext) == ".ply" || std::string(ext) == ".usda") CHECK(r.regions == s.regions);
      fs::remove(part);
    }
    fs::remove(whole);
  }
}

TEST_CASE("a .hair file streams back in chunks; a bad point or a short file is named") {
  StrandSet s = StrandSet::uniform(9, 5, std::vector<float>(9 * 5 * 3, 0.5f));
  for (std::size_t i = 0; i < s.points.size(); ++i) s.points[i] = float(i);
  const fs::path path = temp("uniform.hair");
  write_hair(path, StrandStream::of(s));
  for (std::uint64_t chunk : {1u, 4u, 1000u}) {
    const StrandStream in = stream_hair_file(path, chunk);
    CHECK(in.strands == 9);
    CHECK(in.points == 45);
    CHECK(in.points_in(3) == 5);
    std::vector<float> all;
    std::size_t calls = 0;
    in.each_chunk([&](std::span<const float> xyz) {
      CHECK(xyz.size() <= 3 * chunk);
      all.insert(all.end(), xyz.begin(), xyz.end());
      ++calls;
    });
    CHECK(all == s.points);
    CHECK(calls == (45 + chunk - 1) / chunk);
  }
  s.points[7] = std::nanf("");
  CHECK_THROWS_WITH_AS(write_hair(temp("nan.hair"), StrandStream::of(s)), doctest::Contains("strand point 2 is not finite"), InputError);
  CHECK_FALSE(fs::exists(temp("nan.hair")));
  const std::string bytes = slurp(path);
  std::ofstream(temp("short.hair"), std::ios::binary) << bytes.substr(0, bytes.size() - 20);
  CHECK_THROWS_WITH_AS(stream_hair_file(temp("short.hair")), doctest::Contains("short.hair"), InputError);
}

TEST_CASE("a .usda groom with its body: prims, types and array lengths as USD requires") {
  const StrandSet s = groom(25, 2);
  geometry::Mesh body;
  body.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  body.triangles = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
  body.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  body.regions = {1, 2, 3, 4};
  UsdaScene scene;
  scene.meters_per_unit = 1;
  scene.body = &body;
  const std::vector<float> body_colors = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f, 0.8f, 0.9f, 1.f, 0.5f, 0.f};
  scene.body_colors = body_colors;
  scene.root_face = [](std::uint64_t i) { return std::uint32_t(i % 4); };
  scene.root_barycentric = [](std::uint64_t) { return glm::vec3(0.2f, 0.3f, 0.5f); };
  const fs::path path = temp("groom.usda");
  write_strands_usda(path, StrandStream::of(s), scene);
  const std::string text = slurp(path);
  CHECK(text.rfind("#usda 1.0", 0) == 0);
  CHECK(text.find("defaultPrim = \"animal\"") != std::string::npos);
  CHECK(text.find("metersPerUnit = 1") != std::string::npos);
  CHECK(text.find("upAxis = \"Y\"") != std::string::npos);
  const std::size_t xform = text.find("def Xform \"animal\""), curves = text.find("def BasisCurves \"fur\""), mesh = text.find("def Mesh \"body\"");
  REQUIRE(xform != std::string::npos);
  REQUIRE(curves != std::string::npos);
  REQUIRE(mesh != std::string::npos);
  CHECK((xform < curves && curves < mesh));
  // Braces balance: both prims sit inside the Xform.
  CHECK(std::count(text.begin(), text.end(), '{') == 3);
  CHECK(std::count(text.begin(), text.end(), '}') == 3);
  const std::string c = text.substr(curves, mesh - curves), m = text.substr(mesh);
  CHECK(c.find("uniform token type = \"linear\"") != std::string::npos);
  CHECK(array_length(c, "int[] curveVertexCounts", 1) == 25);
  CHECK(array_length(c, "point3f[] points", 3) == s.point_count());
  CHECK(array_length(c, "float[] widths", 1) == s.point_count());
  CHECK(array_length(c, "int[] primvars:region", 1) == 25);
  CHECK(array_length(c, "int[] primvars:rootFace", 1) == 25);
  CHECK(array_length(c, "float3[] primvars:rootBarycentric", 3) == 25);
  CHECK(array_length(c, "float3[] extent", 3) == 2);
  CHECK(array_length(m, "int[] faceVertexCounts", 1) == 4);
  CHECK(array_length(m, "int[] faceVertexIndices", 1) == 12);
  CHECK(array_length(m, "point3f[] points", 3) == 4);
  CHECK(array_length(m, "normal3f[] normals", 3) == 4);
  CHECK(array_length(m, "int[] primvars:region", 1) == 4);
  CHECK(array_length(m, "color3f[] primvars:displayColor", 3) == 4);  // the body's colours, per vertex
  CHECK(m.find("(0.7, 0.8, 0.9)") != std::string::npos);
  // The reader takes the curves, not the body that follows.
  const StrandSet r = read_strands_usda(path);
  CHECK(r.points == s.points);
  CHECK(r.regions == s.regions);
}

TEST_CASE("a rigged body round-trips through glTF: mesh, joints, parents, bind positions, influences") {
  geometry::Mesh m;
  m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 2, 0};
  m.triangles = {0, 1, 2, 1, 3, 2};
  m.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  m.regions = {0, 1, 2, 3};
  Skeleton s;
  s.joint_names = {"root", "spine", "head"};
  s.parents = {-1, 0, 1};
  s.joint_positions = {{0, 0, 0}, {0, 1, 0}, {0, 1.5f, 0.25f}};
  s.skin_joints = {0, 0, 0, 0, 0, 1, 0, 0, 1, 2, 0, 0, 2, 0, 0, 0};
  s.skin_weights = {1, 0, 0, 0, 0.5f, 0.5f, 0, 0, 0.25f, 0.75f, 0, 0, 1, 0, 0, 0};
  const fs::path path = temp("rigged.glb");
  write_mesh_glb(path, m, &s);
  const geometry::Mesh back = read_mesh_gltf(path);
  CHECK(back.positions == m.positions);
  CHECK(back.triangles == m.triangles);
  CHECK(back.regions == m.regions);
  const Skeleton r = read_skeleton_gltf(path);
  CHECK(r.joint_names == s.joint_names);
  CHECK(r.parents == s.parents);
  for (std::size_t j = 0; j < 3; ++j) CHECK(glm::distance(r.joint_positions[j], s.joint_positions[j]) < 1e-6f);
  CHECK(r.skin_joints == s.skin_joints);
  CHECK(r.skin_weights == s.skin_weights);
  // Bad skeletons are refused before anything is written.
  Skeleton bad = s;
  bad.parents[1] = 2;
  CHECK_THROWS_WITH_AS(write_mesh_glb(temp("bad.glb"), m, &bad), doctest::Contains("not an earlier joint"), InputError);
  bad = s;
  bad.skin_weights[0] = 0.5f;
  CHECK_THROWS_WITH_AS(write_mesh_glb(temp("bad.glb"), m, &bad), doctest::Contains("sum to"), InputError);
  CHECK_FALSE(fs::exists(temp("bad.glb")));
  write_mesh_glb(temp("plain.glb"), m);
  CHECK_THROWS_WITH_AS(read_skeleton_gltf(temp("plain.glb")), doctest::Contains("has no skin"), InputError);
}
