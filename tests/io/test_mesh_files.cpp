// Mesh files: PLY (binary and ASCII, extra properties skipped) and OBJ round trips, and malformed
// files rejected with the file and the field named.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "engine/core/error.hpp"
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
