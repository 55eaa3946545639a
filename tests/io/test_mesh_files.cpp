// Mesh files: PLY (binary and ASCII, extra properties skipped), OBJ and GLB round trips, hand-built
// glTF (external / embedded buffers, node transforms, strides, small indices), and malformed files
// rejected with the file and the field named.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/core/json.hpp"
#include "tests/support/files.hpp"
#include "engine/io/mesh.hpp"

using namespace nf;
using namespace nf::io;
namespace fs = std::filesystem;
using nf::test::slurp;
using nf::test::spit;

namespace {

fs::path temp(const std::string& name) { return fs::temp_directory_path() / ("nf_test_mesh_" + name); }

Mesh tetrahedron(bool extras) {
  Mesh m;
  m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  m.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  if (extras) {
    for (int v = 0; v < 4; ++v) {
      const float n = 1.f / std::sqrt(3.f);
      m.normals.insert(m.normals.end(), {n, n, n});
      m.regions.push_back(v * 3);
    }
  }
  return m;
}

}  // namespace

TEST_CASE("PLY and OBJ meshes round-trip, with normals and regions where the format holds them") {
  for (bool extras : {false, true})
    for (const char* ext : {".ply", ".obj"}) {
      CAPTURE(ext);
      CAPTURE(extras);
      const Mesh m = tetrahedron(extras);
      const fs::path path = temp(std::string("tet") + ext);
      write_mesh(path, m);
      const Mesh r = read_mesh(path);
      CHECK(r.positions == m.positions);
      CHECK(r.triangles == m.triangles);
      CHECK(r.normals == m.normals);
      if (std::string(ext) == ".ply") CHECK(r.regions == m.regions);
      fs::remove(path);
    }
  const fs::path empty = temp("empty.ply");
  write_mesh(empty, Mesh{});
  CHECK(read_mesh(empty).vertex_count() == 0);
  fs::remove(empty);
}

TEST_CASE("ASCII PLY with other properties and polygons, and OBJ quads with v//vn, are read") {
  const fs::path ply = temp("ascii.ply");
  spit(ply,
       "ply\nformat ascii 1.0\ncomment a quad\nelement vertex 4\nproperty double x\nproperty double y\n"
       "property double z\nproperty uchar red\nproperty int label\nelement face 1\n"
       "property list uchar int vertex_indices\nproperty float quality\nend_header\n"
       "0 0 0 255 1\n1 0 0 255 1\n1 1 0 255 2\n0 1 0 255 2\n4 0 1 2 3 0.5\n");
  const Mesh m = read_mesh_ply(ply);
  CHECK(m.vertex_count() == 4);
  CHECK(m.triangles == std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3});
  CHECK(m.regions == std::vector<std::int32_t>{1, 1, 2, 2});
  const fs::path obj = temp("quad.obj");
  spit(obj, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n");
  const Mesh q = read_mesh_obj(obj);
  CHECK(q.triangle_count() == 2);
  CHECK(q.normals[2] == 1.f);
  fs::remove(ply);
  fs::remove(obj);
}

TEST_CASE("malformed meshes name the file and the field") {
  const fs::path ply = temp("bad.ply"), obj = temp("bad.obj");
  write_mesh_ply(ply, tetrahedron(true));
  std::ifstream in(ply, std::ios::binary);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  spit(ply, good.substr(0, good.size() - 6));
  CHECK_THROWS_WITH_AS(read_mesh_ply(ply), doctest::Contains("element 'face' 3"), InputError);
  spit(ply, "ply\nformat binary_big_endian 1.0\nend_header\n");
  CHECK_THROWS_WITH_AS(read_mesh_ply(ply), doctest::Contains("binary_big_endian"), InputError);
  spit(ply, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n3 0 0 5\n");
  CHECK_THROWS_WITH_AS(read_mesh_ply(ply), doctest::Contains("uses vertex 5"), InputError);
  spit(ply, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
            "end_header\nnan 0 0\n");
  CHECK_THROWS_WITH_AS(read_mesh_ply(ply), doctest::Contains("vertex' 0 property 'x'"), InputError);
  spit(obj, "v 0 0 0\nf 1 2 3\n");
  CHECK_THROWS_WITH_AS(read_mesh_obj(obj), doctest::Contains("line 2: vertex index 2"), InputError);
  spit(obj, "v 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 x 3\n");
  CHECK_THROWS_WITH_AS(read_mesh_obj(obj), doctest::Contains("bad face corner 'x'"), InputError);
  CHECK_THROWS_WITH_AS(read_mesh(temp("x.stl")), doctest::Contains("unknown mesh format"), InputError);
  fs::remove(ply);
  fs::remove(obj);
}

// ---- glTF 2.0 / GLB ----

namespace {

template <class T>
std::string raw(std::initializer_list<T> values) {
  std::string s(values.size() * sizeof(T), '\0');
  std::memcpy(s.data(), std::data(values), s.size());
  return s;
}

std::string glb(const std::string& text, const std::string& bin) {
  std::string j = text, b = bin;
  j.resize((j.size() + 3) / 4 * 4, ' ');
  b.resize((b.size() + 3) / 4 * 4, '\0');
  const auto total = std::uint32_t(12 + 8 + j.size() + (b.empty() ? 0 : 8 + b.size()));
  std::string out = raw<std::uint32_t>({0x46546C67, 2, total, std::uint32_t(j.size()), 0x4E4F534A}) + j;
  if (!b.empty()) out += raw<std::uint32_t>({std::uint32_t(b.size()), 0x004E4942}) + b;
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t v = std::uint32_t(std::uint8_t(bytes[i])) << 16;
    if (i + 1 < bytes.size()) v |= std::uint32_t(std::uint8_t(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) v |= std::uint8_t(bytes[i + 2]);
    out += digits[(v >> 18) & 63];
    out += digits[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? digits[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? digits[v & 63] : '=';
  }
  return out;
}

// A triangle in the xy plane with +z normals and u32 indices: accessors 0 POSITION, 1 NORMAL, 2 indices.
struct Asset {
  nf::json doc;
  std::string bin;
};

Asset triangle_asset() {
  Asset a;
  a.bin = raw<float>({0, 0, 0, 1, 0, 0, 0, 1, 0}) + raw<float>({0, 0, 1, 0, 0, 1, 0, 0, 1}) + raw<std::uint32_t>({0, 1, 2});
  a.doc = nf::json::parse(R"({
    "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
      {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
      {"bufferView": 2, "componentType": 5125, "count": 3, "type": "SCALAR"}],
    "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 36},
                    {"buffer": 0, "byteOffset": 72, "byteLength": 12}],
    "buffers": [{"byteLength": 84}]})");
  return a;
}

void write_glb(const fs::path& path, const Asset& a) { spit(path, glb(a.doc.dump(), a.bin)); }

}  // namespace

TEST_CASE("GLB meshes round-trip exactly: with and without normals / regions, empty, one triangle, points") {
  std::vector<Mesh> meshes = {tetrahedron(false), tetrahedron(true), Mesh{}};
  meshes[1].regions = {-7, 0, 16777216, 42};
  Mesh one;
  one.positions = {0.1f, -2.5f, 3e-8f, 1e6f, 0, 0, 0, 1, -0.f};
  one.triangles = {0, 1, 2};
  meshes.push_back(one);
  Mesh points = one;
  points.triangles.clear();
  points.regions = {1, 2, 3};
  meshes.push_back(points);
  const fs::path path = temp("round.glb");
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    CAPTURE(k);
    write_mesh(path, meshes[k]);
    const std::string bytes = slurp(path);
    REQUIRE(bytes.size() % 4 == 0);
    CHECK(bytes.substr(0, 4) == "glTF");
    const Mesh r = read_mesh(path);
    CHECK(r.positions == meshes[k].positions);
    CHECK(r.triangles == meshes[k].triangles);
    CHECK(r.normals == meshes[k].normals);
    CHECK(r.regions == meshes[k].regions);
  }
  // What the writer declares: generator, min / max, _REGION as FLOAT, indices as UNSIGNED_INT.
  write_mesh_glb(path, tetrahedron(true));
  const std::string bytes = slurp(path);
  std::uint32_t json_length;
  std::memcpy(&json_length, bytes.data() + 12, 4);
  const nf::json doc = nf::json::parse(bytes.substr(20, json_length));
  CHECK(doc["asset"]["generator"] == "nf_gpu; nf_gpu frame: scene");  // the frame it states (file_frame.hpp)
  CHECK(nf::io::declared_frame(path) == nf::io::FileFrame::scene);
  write_mesh_glb(path, tetrahedron(true), nullptr, nf::io::FileFrame::exported);
  CHECK(nf::io::declared_frame(path) == nf::io::FileFrame::exported);
  write_mesh_glb(path, tetrahedron(true));
  CHECK(doc["accessors"][0]["max"] == nf::json::array({1.0, 1.0, 1.0}));
  const auto& prim = doc["meshes"][0]["primitives"][0];
  CHECK(prim["mode"] == 4);
  CHECK(doc["accessors"][prim["attributes"]["_REGION"].get<int>()]["componentType"] == 5126);
  CHECK(doc["accessors"][prim["indices"].get<int>()]["componentType"] == 5125);
  Mesh big = tetrahedron(true);
  big.regions[2] = 16777217;
  CHECK_THROWS_WITH_AS(write_mesh_glb(path, big), doctest::Contains("vertex 2"), InputError);
  CHECK_THROWS_WITH_AS(write_mesh(temp("x.gltf"), big), doctest::Contains("use .glb"), InputError);
  // Vertex colours: COLOR_0, FLOAT VEC3, the values as given; the mesh reads back the same; a
  // count that is not the vertices' or a colour outside [0, 1] (glTF's rule) is refused, naming the file.
  const std::vector<float> colors = {0.f, 0.25f, 1.f, 0.5f, 0.5f, 0.5f, 1.f, 0.f, 0.f, 0.02f, 0.9f, 0.3f};
  write_mesh_glb(path, tetrahedron(true), nullptr, nf::io::FileFrame::scene, colors);
  {
    const std::string b = slurp(path);
    std::uint32_t n_json, n_bin;
    std::memcpy(&n_json, b.data() + 12, 4);
    std::memcpy(&n_bin, b.data() + 20 + n_json, 4);
    const nf::json d = nf::json::parse(b.substr(20, n_json));
    const auto& a = d["accessors"][d["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"].get<int>()];
    CHECK(a["componentType"] == 5126);
    CHECK(a["type"] == "VEC3");
    CHECK(a["count"] == 4);
    const auto& view = d["bufferViews"][a["bufferView"].get<int>()];
    std::vector<float> stored(12);
    std::memcpy(stored.data(), b.data() + 20 + n_json + 8 + view["byteOffset"].get<std::size_t>(), 48);
    CHECK(stored == colors);
    CHECK(read_mesh(path).positions == tetrahedron(true).positions);
  }
  CHECK_THROWS_WITH_AS(write_mesh_glb(path, tetrahedron(true), nullptr, nf::io::FileFrame::scene, std::span<const float>(colors).first(9)),
                       doctest::Contains("3 vertex colours for 4 vertices"), InputError);
  for (const float bad : {-0.5f, 1.5f, std::nanf("")}) {
    std::vector<float> out_of_range = colors;
    out_of_range[4] = bad;
    CHECK_THROWS_WITH_AS(write_mesh_glb(path, tetrahedron(true), nullptr, nf::io::FileFrame::scene, out_of_range), doctest::Contains(path.string().c_str()), InputError);
  }
  fs::remove(path);
}

TEST_CASE(".gltf with an external .bin or a base64 data URI, with a node hierarchy, is flattened") {
  Asset a = triangle_asset();
  // Root 0: translate (10,0,0), child 1: rotate 90 degrees about z and scale 2. Root 2: mirror x, z += 5.
  const double h = std::sqrt(0.5);
  a.doc["scenes"][0]["nodes"] = {0, 2};
  a.doc["nodes"] = nf::json::array({nf::json{{"translation", {10, 0, 0}}, {"children", {1}}},
                                    nf::json{{"rotation", {0, 0, h, h}}, {"scale", {2, 2, 2}}, {"mesh", 0}},
                                    nf::json{{"matrix", {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 5, 1}}, {"mesh", 0}}});
  const fs::path gltf = temp("tri.gltf"), bin = temp("tri data.bin");
  spit(bin, a.bin);
  a.doc["buffers"][0]["uri"] = "nf_test_mesh_tri%20data.bin";
  spit(gltf, a.doc.dump(2));
  const Mesh external = read_mesh(gltf);
  a.doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(a.bin);
  spit(gltf, a.doc.dump());
  const Mesh embedded = read_mesh(gltf);
  for (const Mesh* m : {&external, &embedded}) {
    REQUIRE(m->vertex_count() == 6);
    const std::vector<float> expected = {10, 0, 0, 10, 2, 0, 8, 0, 0, 0, 0, 5, -1, 0, 5, 0, 1, 5};
    for (std::size_t i = 0; i < expected.size(); ++i) CHECK(m->positions[i] == doctest::Approx(expected[i]).epsilon(1e-6));
    for (std::size_t v = 0; v < 6; ++v) CHECK(m->normals[3 * v + 2] == doctest::Approx(1.0));
    CHECK(m->triangles == std::vector<std::uint32_t>{0, 1, 2, 3, 5, 4});  // the mirrored copy keeps CCW
    CHECK(m->regions.empty());
  }
  fs::remove(bin);
  CHECK_THROWS_WITH_AS(read_mesh(gltf.string() + "x"), doctest::Contains("unknown mesh format"), InputError);
  a.doc["buffers"][0]["uri"] = "nf_test_mesh_tri%20data.bin";
  spit(gltf, a.doc.dump());
  CHECK_THROWS_WITH_AS(read_mesh(gltf), doctest::Contains("buffers[0].uri"), InputError);
  a.doc["buffers"][0]["uri"] = "https://example.com/tri.bin";
  spit(gltf, a.doc.dump());
  CHECK_THROWS_WITH_AS(read_mesh(gltf), doctest::Contains("neither a relative file path"), InputError);
  fs::remove(gltf);
}

TEST_CASE("glTF interleaved buffers (byteStride), u8 / u16 indices, integer _REGION, strips and fans") {
  // 8 bytes of padding, then 4 vertices as px py pz nx ny nz (stride 24), then indices and regions.
  std::string bin = std::string(8, 'x');
  const float quad[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  for (const auto& q : quad) bin += raw<float>({q[0], q[1], q[2], 0, 0, 1});
  const std::size_t indices_at = bin.size();
  bin += raw<std::uint16_t>({0, 1, 2, 0, 2, 3}) + raw<std::uint8_t>({0, 1, 2, 0, 2, 3, 0, 0});
  const std::size_t regions_at = bin.size();
  bin += raw<std::uint16_t>({5, 5, 9, 9});
  nf::json doc = nf::json::parse(R"({
    "asset": {"version": "2.0"}, "meshes": [{"primitives": [
      {"attributes": {"POSITION": 0, "NORMAL": 1, "_REGION": 3}, "indices": 2, "mode": 4}]}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
      {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC3"},
      {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
      {"bufferView": 2, "componentType": 5123, "count": 4, "type": "SCALAR"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 8, "byteLength": 96, "byteStride": 24},
                    {"buffer": 0, "byteLength": 20}, {"buffer": 0, "byteLength": 8}]})");
  doc["bufferViews"][1]["byteOffset"] = indices_at;
  doc["bufferViews"][2]["byteOffset"] = regions_at;
  doc["buffers"] = nf::json::array({nf::json{{"byteLength", bin.size()}}});
  const fs::path path = temp("interleaved.glb");
  const std::vector<std::uint32_t> two = {0, 1, 2, 0, 2, 3};
  // No scenes: every mesh once, untransformed.
  spit(path, glb(doc.dump(), bin));
  Mesh m = read_mesh(path);
  CHECK(m.positions == std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
  CHECK(m.normals == std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1});
  CHECK(m.triangles == two);
  CHECK(m.regions == std::vector<std::int32_t>{5, 5, 9, 9});
  // u8 indices: the same bytes after the six u16.
  doc["accessors"][2]["componentType"] = 5121;
  doc["accessors"][2]["byteOffset"] = 12;
  spit(path, glb(doc.dump(), bin));
  CHECK(read_mesh(path).triangles == two);
  // Non-indexed strip and fan over the 4 vertices; lines are skipped.
  doc["meshes"][0]["primitives"][0].erase("indices");
  doc["meshes"][0]["primitives"][0]["mode"] = 5;
  spit(path, glb(doc.dump(), bin));
  CHECK(read_mesh(path).triangles == std::vector<std::uint32_t>{0, 1, 2, 1, 3, 2});
  doc["meshes"][0]["primitives"][0]["mode"] = 6;
  spit(path, glb(doc.dump(), bin));
  CHECK(read_mesh(path).triangles == std::vector<std::uint32_t>{1, 2, 0, 2, 3, 0});
  doc["meshes"][0]["primitives"][0]["mode"] = 1;
  spit(path, glb(doc.dump(), bin));
  CHECK(read_mesh(path).vertex_count() == 0);
  fs::remove(path);
}

TEST_CASE("malformed glTF / GLB files name the file and the field") {
  const fs::path path = temp("bad.glb");
  const Asset good = triangle_asset();
  auto fails = [&](const Asset& a, const char* expected) {
    CAPTURE(expected);
    write_glb(path, a);
    CHECK_THROWS_WITH_AS(read_mesh(path), doctest::Contains(expected), InputError);
  };
  write_glb(path, good);
  CHECK(read_mesh(path).triangle_count() == 1);
  const std::string bytes = slurp(path);
  spit(path, bytes.substr(0, bytes.size() - 5));
  CHECK_THROWS_WITH_AS(read_mesh(path), doctest::Contains("GLB header length"), InputError);
  spit(path, bytes.substr(0, 7));
  CHECK_THROWS_WITH_AS(read_mesh(path), doctest::Contains("12-byte GLB header"), InputError);
  spit(path, "glTX" + bytes.substr(4));
  CHECK_THROWS_WITH_AS(read_mesh(path), doctest::Contains("GLB magic"), InputError);
  std::string long_chunk = bytes;
  long_chunk[12] = char(0xF0);
  spit(path, long_chunk);
  CHECK_THROWS_WITH_AS(read_mesh(path), doctest::Contains("GLB chunk 0 length"), InputError);
  spit(path, glb("{\"asset\": {\"version\": \"2.0\"", ""));
  CHECK_THROWS_WITH_AS(read_mesh(path), doctest::Contains("JSON chunk is malformed"), InputError);

  Asset a = good;
  a.doc["accessors"][0]["count"] = 100;
  fails(a, "accessors[0].count 100 exceeds bufferViews[0]");
  a = good;
  a.doc["accessors"][1]["byteOffset"] = 4;
  fails(a, "accessors[1].count 3 exceeds bufferViews[1]");
  a = good;
  a.doc["bufferViews"][2]["byteOffset"] = 80;
  fails(a, "bufferViews[2]: byteOffset 80 + byteLength 12 exceeds buffers[0]");
  a = good;
  a.doc["buffers"][0]["byteLength"] = 1000;
  fails(a, "buffers[0].byteLength 1000 exceeds the GLB BIN chunk");
  a = good;
  a.doc["accessors"][2]["count"] = 2;
  fails(a, "accessors[2].count 2");
  a = good;
  a.bin.replace(72, 4, raw<std::uint32_t>({7}));
  fails(a, "accessors[2] element 0 (meshes[0].primitives[0].indices) is vertex 7");
  a = good;
  a.bin.replace(12, 4, raw<float>({std::nanf("")}));
  fails(a, "accessors[0] element 1 (meshes[0].primitives[0].attributes.POSITION) is nan");
  a = good;
  a.doc["accessors"][0]["sparse"] = nf::json::object();
  fails(a, "accessors[0] (meshes[0].primitives[0].attributes.POSITION) is sparse");
  a = good;
  a.doc["accessors"][0]["componentType"] = 5123;
  fails(a, "accessors[0].componentType 5123 (UNSIGNED_SHORT) is not read");
  a = good;
  a.doc["accessors"][1]["type"] = "VEC4";
  fails(a, "accessors[1].type is 'VEC4', not VEC3");
  a = good;
  a.doc["accessors"][0]["count"] = 1.5;
  fails(a, "accessors[0].count is 1.5");
  a = good;
  a.doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 9;
  fails(a, "meshes[0].primitives[0].attributes.POSITION is 9 but the file has 3 accessors");
  a = good;
  a.doc["bufferViews"][0]["byteStride"] = 4;
  fails(a, "bufferViews[0].byteStride 4 is smaller");
  a = good;
  a.doc["nodes"][0]["children"] = {0};
  fails(a, "nodes[0] is reached twice");
  a = good;
  a.doc["asset"]["version"] = "1.0";
  fails(a, "asset.version is '1.0'");
  a = good;
  a.doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  fails(a, "extensionsRequired[0] is KHR_draco_mesh_compression");
  a = good;
  a.doc["nodes"][0]["matrix"] = {1, 0, 0};
  fails(a, "nodes[0].matrix is not an array of 16 numbers");
  a = good;
  a.doc["buffers"][0]["uri"] = "data:application/octet-stream;base64,@@@";
  fails(a, "buffers[0].uri");
  fs::remove(path);
}

TEST_CASE("a rigged glTF's skin is read from u8 or u16 joints, and its accessors are bounds-checked like the mesh's") {
  // The triangle with a one-joint skin: JOINTS_0 (u16 VEC4) at byte 84, WEIGHTS_0 (f32 VEC4) at 108,
  // the inverse bind matrix (which tinygltf requires) at 156.
  Asset a = triangle_asset();
  a.bin += raw<std::uint16_t>({0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}) + raw<float>({1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0}) +
           raw<float>({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -0.5f, 0, 0, 1});
  a.doc["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = 3;
  a.doc["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"] = 4;
  a.doc["accessors"].push_back({{"bufferView", 3}, {"componentType", 5123}, {"count", 3}, {"type", "VEC4"}});
  a.doc["accessors"].push_back({{"bufferView", 4}, {"componentType", 5126}, {"count", 3}, {"type", "VEC4"}});
  a.doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 84}, {"byteLength", 24}});
  a.doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 108}, {"byteLength", 48}});
  a.doc["accessors"].push_back({{"bufferView", 5}, {"componentType", 5126}, {"count", 1}, {"type", "MAT4"}});
  a.doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 156}, {"byteLength", 64}});
  a.doc["buffers"][0]["byteLength"] = 220;
  a.doc["nodes"][0]["skin"] = 0;
  a.doc["nodes"].push_back({{"name", "root"}, {"translation", {0.5, 0, 0}}});
  a.doc["scenes"][0]["nodes"].push_back(1);
  a.doc["skins"] = nf::json::array({{{"joints", {1}}, {"inverseBindMatrices", 5}}});
  const fs::path path = temp("skinned.glb");
  write_glb(path, a);
  const Skeleton s = read_skeleton_gltf(path);
  CHECK(s.joint_names == std::vector<std::string>{"root"});
  CHECK(s.joint_positions[0] == glm::vec3(0.5f, 0, 0));
  CHECK(s.skin_joints == std::vector<std::uint16_t>(12, 0));
  CHECK(s.skin_weights == std::vector<float>{1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0});
  // u8 joints: the first 12 of the same zero bytes.
  Asset bytes = a;
  bytes.doc["accessors"][3]["componentType"] = 5121;
  write_glb(path, bytes);
  CHECK(read_skeleton_gltf(path).skin_joints == std::vector<std::uint16_t>(12, 0));
  auto fails = [&](const Asset& bad, const char* expected) {
    CAPTURE(expected);
    write_glb(path, bad);
    CHECK_THROWS_WITH_AS(read_skeleton_gltf(path), doctest::Contains(expected), InputError);
  };
  // A count whose byte size wraps 64 bits once was a std::length_error (found by fuzz_skeleton_gltf).
  Asset bad = a;
  bad.doc["accessors"][3]["count"] = std::uint64_t(1) << 62;
  fails(bad, "accessors[3].count 4611686018427387904 exceeds bufferViews[3]");
  bad = a;
  bad.doc["accessors"][4]["count"] = 2;
  fails(bad, "JOINTS_0 has 3 elements, WEIGHTS_0 2");
  bad = a;
  bad.doc["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"] = 9;
  fails(bad, "attributes.WEIGHTS_0 is 9 but the file has 6 accessors");
  bad = a;
  bad.doc["accessors"][4]["componentType"] = 5123;
  fails(bad, "is not read for meshes[0].primitives[0].attributes.WEIGHTS_0 (FLOAT)");
  bad = a;
  bad.doc["bufferViews"][4]["byteStride"] = 8;
  fails(bad, "byteStride 8 is smaller than the 16-byte elements");
  fs::remove(path);
}

TEST_CASE("glTF through tinygltf: images are never decoded, buffers match byteLength, nothing deep or foreign is followed") {
  const fs::path glb_path = temp("lib.glb"), gltf = temp("lib.gltf"), bin = temp("lib.bin");
  Asset a = triangle_asset();
  // Images of every kind (an external file that does not exist, a data: URI, a bufferView) are skipped.
  a.doc["images"] = {nf::json{{"uri", "no_such_texture.png"}}, nf::json{{"uri", "data:image/png;base64,AAAA"}},
                     nf::json{{"bufferView", 2}, {"mimeType", "image/png"}}};
  write_glb(glb_path, a);
  CHECK(read_mesh(glb_path).triangle_count() == 1);
  // A JSON chunk padded with NULs (some writers do) is read.
  std::string text = triangle_asset().doc.dump();
  text.resize((text.size() + 3) / 4 * 4 + 4, '\0');
  std::string bytes = glb(text, a.bin);
  spit(glb_path, bytes);
  CHECK(read_mesh(glb_path).triangle_count() == 1);
  // Extras nested beyond what tinygltf's recursive copy survives are refused, not a crash.
  a = triangle_asset();
  std::string deep = a.doc.dump();
  deep.insert(deep.size() - 1, ",\"extras\":" + std::string(100000, '[') + std::string(100000, ']'));
  spit(glb_path, glb(deep, a.bin));
  CHECK_THROWS_WITH_AS(read_mesh(glb_path), doctest::Contains("levels deep"), InputError);
  // An external .bin must hold exactly byteLength bytes; a missing one is named; http: is refused.
  a = triangle_asset();
  a.doc["buffers"][0]["uri"] = "nf_test_mesh_lib.bin";
  spit(gltf, a.doc.dump());
  spit(bin, a.bin);
  CHECK(read_mesh(gltf).triangle_count() == 1);
  spit(bin, a.bin + "xxxx");
  CHECK_THROWS_WITH_AS(read_mesh(gltf), doctest::Contains("buffers[0].byteLength 84 differs from the size of"), InputError);
  fs::remove(bin);
  CHECK_THROWS_WITH_AS(read_mesh(gltf), doctest::Contains("nf_test_mesh_lib.bin is missing"), InputError);
  a.doc["buffers"][0]["uri"] = "http://example.com/nf_test_mesh_lib.bin";
  spit(gltf, a.doc.dump());
  CHECK_THROWS_WITH_AS(read_mesh(gltf), doctest::Contains("nothing is downloaded"), InputError);
  // Fields tinygltf would read silently as defaults are refused by name.
  a = triangle_asset();
  a.doc["meshes"][0]["primitives"][0]["indices"] = "2";
  write_glb(glb_path, a);
  CHECK_THROWS_WITH_AS(read_mesh(glb_path), doctest::Contains("meshes[0].primitives[0].indices is \"2\""), InputError);
  a = triangle_asset();
  a.doc["bufferViews"][1]["byteOffset"] = 36.5;
  write_glb(glb_path, a);
  CHECK_THROWS_WITH_AS(read_mesh(glb_path), doctest::Contains("bufferViews[1].byteOffset is 36.5"), InputError);
  fs::remove(glb_path);
  fs::remove(gltf);
}
