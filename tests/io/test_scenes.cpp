// Camera formats: transforms.json round-trips; NeuS, Artemis and COLMAP fixtures written from the
// same cameras agree with it to 1e-5 (intrinsics, poses and projected points); distortion and bad
// input are refused with the file and field named (a JSON type error by its path, not the JSON
// library's text); a truncated image is found by the file check that runs before any stage.
#include <doctest/doctest.h>

#include <zip.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/io/image.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/io/npz.hpp"
#include "engine/io/scene.hpp"
#include "tests/support/files.hpp"
#include "tests/support/scene_fixtures.hpp"

using namespace nf;
using namespace nf::io;
namespace fs = std::filesystem;

namespace {

const std::uint32_t kW = 320, kH = 240;

// A complete black PNG: image sizes are read by stb, which wants a whole header (and the file check
// wants a whole file).
void write_png_file(const fs::path& path, std::uint32_t w, std::uint32_t h) {
  write_png(path, Image{w, h, 1, std::vector<float>(std::size_t(w) * h, 0.f)});
}

// Eight cameras on a ring, 3 units away, looking at the origin (OpenGL axes).
std::vector<Camera> ring() {
  std::vector<Camera> cams;
  for (int i = 0; i < 8; ++i) {
    const double a = 2 * 3.14159265358979 * i / 8;
    const glm::dvec3 eye(3 * std::cos(a), 0.5 + 0.1 * i, 3 * std::sin(a));
    const glm::dvec3 forward = glm::normalize(-eye), right = glm::normalize(glm::cross(forward, glm::dvec3(0, 1, 0)));
    const glm::dvec3 up = glm::cross(right, forward);
    Camera c;
    c.name = "cam" + std::to_string(i);
    c.width = kW, c.height = kH;
    c.fx = 300 + i, c.fy = 301 + i, c.cx = 160.5, c.cy = 119.5;
    c.camera_to_world = glm::dmat4(glm::dvec4(right, 0), glm::dvec4(up, 0), glm::dvec4(-forward, 0), glm::dvec4(eye, 1));
    cams.push_back(c);
  }
  return cams;
}

void check_same(const Scene& got, const std::vector<Camera>& want) {
  REQUIRE(got.cameras.size() == want.size());
  const glm::dvec3 probes[3] = {{0, 0, 0}, {0.3, -0.2, 0.1}, {-0.5, 0.4, 0.2}};
  for (std::size_t i = 0; i < want.size(); ++i) {
    const Camera &g = got.cameras[i], &w = want[i];
    CAPTURE(i);
    CHECK(g.width == w.width);
    CHECK(g.height == w.height);
    CHECK(std::fabs(g.fx - w.fx) < 1e-5 * w.fx);
    CHECK(std::fabs(g.fy - w.fy) < 1e-5 * w.fy);
    CHECK(std::fabs(g.cx - w.cx) < 1e-5 * w.cx);
    CHECK(std::fabs(g.cy - w.cy) < 1e-5 * w.cy);
    for (int r = 0; r < 4; ++r)
      for (int k = 0; k < 4; ++k) CHECK(std::fabs(g.camera_to_world[r][k] - w.camera_to_world[r][k]) < 1e-5);
    for (const auto& p : probes) {
      const glm::dvec3 a = g.project(p), b = w.project(p);
      CHECK(glm::length(a - b) < 1e-5 * glm::length(b));
    }
  }
}

}  // namespace

TEST_CASE("a camera's unproject inverts its project, its rays start at its centre, and a pose inverted once projects alike") {
  Camera c;
  c.width = 640, c.height = 480, c.fx = 500, c.fy = 520, c.cx = 322.5, c.cy = 236.0;
  const double a = 0.7;  // turned about y, moved off the origin
  c.camera_to_world = glm::dmat4(glm::dvec4(std::cos(a), 0, -std::sin(a), 0), glm::dvec4(0, 1, 0, 0),
                                 glm::dvec4(std::sin(a), 0, std::cos(a), 0), glm::dvec4(1.5, -0.4, 2.0, 1));
  CHECK(glm::length(c.centre() - glm::dvec3(1.5, -0.4, 2.0)) < 1e-12);
  for (const glm::dvec3& p : {glm::dvec3(0.1, 0.2, -0.3), glm::dvec3(-1.0, 0.5, 0.7)}) {
    const glm::dvec3 q = c.project(p);
    REQUIRE(q.z > 0);
    CHECK(glm::length(c.unproject({q.x, q.y}, q.z) - p) < 1e-9);
    CHECK(c.project(p, c.world_to_camera()) == q);  // inverted once for many points: the same, bit for bit
  }
  // The principal point at depth 1 lies one unit down the viewing direction (-z of the camera).
  CHECK(glm::length(c.unproject({c.cx, c.cy}, 1.0) - (c.centre() - glm::dvec3(c.camera_to_world[2]))) < 1e-12);
}

TEST_CASE("transforms.json round-trips, with per-frame intrinsics and masks") {
  const fs::path dir = fs::temp_directory_path() / "nf_scene_transforms";
  fs::create_directories(dir / "images");
  Scene s;
  s.root = dir;
  s.cameras = ring();
  for (auto& c : s.cameras) c.image = dir / "images" / (c.name + ".png"), c.mask = dir / "masks" / (c.name + ".png");
  s.cm_per_unit = 2.5;
  write_transforms_json(dir / "transforms.json", s);
  const Scene r = read_scene(dir);
  check_same(r, s.cameras);
  CHECK(r.cm_per_unit.value() == 2.5);
  CHECK(r.cameras[3].mask == dir / "masks" / "cam3.png");
  fs::remove_all(dir);
}

TEST_CASE("NeuS, Artemis and COLMAP fixtures agree with the cameras they were written from") {
  const auto cams = ring();
  const fs::path root = fs::temp_directory_path() / "nf_scene_formats";
  fs::remove_all(root);

  SUBCASE("NeuS cameras_sphere.npz") {
    fs::create_directories(root / "image");
    fs::create_directories(root / "mask");
    test::write_neus_cameras(root, cams);
    for (std::size_t i = 0; i < cams.size(); ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "%03u.png", unsigned(i));
      write_png_file(root / "image" / name, kW, kH);
      write_png_file(root / "mask" / name, kW, kH);
    }
    check_same(read_scene(root), cams);
  }

  SUBCASE("Artemis CamPose.inf and Intrinsic.inf") {
    fs::create_directories(root);
    test::write_artemis_cameras(root, cams);
    for (std::size_t i = 0; i < cams.size(); ++i) {
      test::write_jpeg_header(root / (test::artemis_name(i) + ".jpg"), kW, kH);
      write_png_file(root / (test::artemis_name(i) + "_alpha.png"), kW, kH);
    }
    const Scene s = read_scene(root);
    check_same(s, cams);
    CHECK(s.cameras[0].mask.filename() == "img_0000_alpha.png");
  }

  SUBCASE("COLMAP text model") {
    fs::create_directories(root);
    test::write_colmap_cameras(root, cams);
    check_same(read_scene(root), cams);
  }
  fs::remove_all(root);
}

TEST_CASE("distortion, missing fields and bad poses are refused with the file and field named") {
  const fs::path dir = fs::temp_directory_path() / "nf_scene_bad";
  fs::create_directories(dir);
  const auto write = [&](const std::string& text) { std::ofstream(dir / "transforms.json") << text; };
  const std::string frame = R"("file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]])";
  write(R"({"fl_x": 300, "w": 64, "h": 48, "k1": 0.1, "frames": [{)" + frame + "}]}");
  CHECK_THROWS_WITH_AS(read_scene(dir), doctest::Contains("lens distortion ('k1')"), InputError);
  write(R"({"fl_x": 300, "w": 64, "frames": [{)" + frame + "}]}");
  CHECK_THROWS_WITH_AS(read_scene(dir), doctest::Contains("field 'h' is missing"), InputError);
  write(R"({"fl_x": 300, "w": 64, "h": 48, "frames": [{"file_path": "a.png", "transform_matrix": [[2,0,0,0],[0,1,0,0],[0,0,1,0]]}]})");
  CHECK_THROWS_WITH_AS(read_scene(dir), doctest::Contains("not orthonormal"), InputError);
  write("{ not json");
  CHECK_THROWS_WITH_AS(read_scene(dir), doctest::Contains("not valid JSON"), InputError);
  fs::remove(dir / "transforms.json");
  std::ofstream(dir / "cameras.txt") << "1 OPENCV 64 48 300 300 32 24 0.1 0 0 0\n";
  std::ofstream(dir / "images.txt") << "";
  CHECK_THROWS_WITH_AS(read_scene(dir), doctest::Contains("lens distortion"), InputError);
  fs::remove_all(dir);
  CHECK_THROWS_WITH_AS(read_scene(dir), doctest::Contains("no scene found"), InputError);
}

TEST_CASE("COLMAP's project layout: the model in sparse/0, the photos in images/ beside it") {
  const fs::path dir = fs::temp_directory_path() / "nf_scene_colmap_project";
  fs::remove_all(dir);
  fs::create_directories(dir / "sparse" / "0");
  std::ofstream(dir / "sparse" / "0" / "cameras.txt") << "# a comment\n1 PINHOLE 64 48 300 300 32 24\n";
  std::ofstream(dir / "sparse" / "0" / "images.txt") << "1 1 0 0 0 0 0 2 1 a.jpg\n\n";
  const Scene s = read_scene(dir);
  REQUIRE(s.cameras.size() == 1);
  CHECK(s.cameras[0].image == dir / "images" / "a.jpg");
  CHECK(s.cameras[0].centre().z == doctest::Approx(-2.0));  // -R^T t with R = I, t = (0, 0, 2)
  CHECK(s.cameras[0].mask.empty());
  fs::remove_all(dir);
}

TEST_CASE("scene files: missing images, wrong sizes and masks that do not match are named") {
  const fs::path dir = fs::temp_directory_path() / "nf_scene_files";
  fs::remove_all(dir);
  fs::create_directories(dir / "images");
  fs::create_directories(dir / "masks");
  Scene s;
  s.root = dir;
  s.cameras = ring();
  s.cameras.resize(2);
  for (auto& c : s.cameras) {
    c.image = dir / "images" / (c.name + ".png"), c.mask = dir / "masks" / (c.name + ".png");
    write_png_file(c.image, kW, kH);
    write_png_file(c.mask, kW, kH);
  }
  CHECK_NOTHROW(s.check_files("scene"));
  write_png_file(s.cameras[1].mask, kW, kH + 1);
  CHECK_THROWS_WITH_AS(s.check_files("scene"), doctest::Contains("camera 'cam1': mask"), InputError);
  CHECK_THROWS_WITH_AS(s.check_files("scene"), doctest::Contains("is 320x241 but the camera is 320x240"), InputError);
  write_png_file(s.cameras[1].mask, kW, kH);
  write_png_file(s.cameras[0].image, kW / 2, kH);
  CHECK_THROWS_WITH_AS(s.check_files("scene"), doctest::Contains("camera 'cam0': image"), InputError);
  fs::remove(s.cameras[0].image);
  CHECK_THROWS_WITH_AS(s.check_files("scene"), doctest::Contains("does not exist"), InputError);
  std::ofstream(s.cameras[0].image) << "not a png";
  CHECK_THROWS_AS(s.check_files("scene"), InputError);
  // A name the file system refuses (longer than a file name may be) is the camera's bad input, not
  // a std::filesystem exception (found by fuzz_scene_text).
  s.cameras[0].image = dir / "images" / std::string(300, 'I');
  CHECK_THROWS_WITH_AS(s.check_files("scene"), doctest::Contains("camera 'cam0': image"), InputError);
  CHECK_THROWS_WITH_AS(s.check_files("scene"), doctest::Contains("cannot be read"), InputError);
  fs::remove_all(dir);
}

TEST_CASE("transforms.json: a value of the wrong type is named by its path, not by the JSON library") {
  const fs::path dir = fs::temp_directory_path() / "nf_scene_types";
  fs::create_directories(dir);
  const fs::path file = dir / "transforms.json";
  const auto message = [&](const std::string& text) {
    std::ofstream(file) << text;
    try {
      (void)read_scene(dir);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string good = R"("file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]])";
  const std::string bad = R"("file_path": "b.png", "transform_matrix": [[1,0,0,0],[0,1,"a",0],[0,0,1,0],[0,0,0,1]])";
  std::string m = message(R"({"fl_x": 300, "w": 64, "h": 48, "frames": [{)" + good + "}, {" + good + "}, {" + good +
                          "}, {" + bad + "}]}");
  CHECK(m.find(file.string() + ": frames[3].transform_matrix[1][2]: expected a number, got \"a\"") != std::string::npos);
  CHECK(m.find("json.exception") == std::string::npos);
  m = message(R"({"fl_x": 300, "w": "64", "h": 48, "frames": [{)" + good + "}]}");
  CHECK(m.find("w: expected a number, got \"64\"") != std::string::npos);
  // A long text is cut at a character boundary, never inside one (the fuzzer's finding: cut inside
  // a two-byte character, the message itself could not be written).
  m = message(R"({"fl_x": 300, "w": "abcdefghijklmnopqrstuvwxyz0123456789abcééé", "h": 48, "frames": [{)" + good + "}]}");
  CHECK(m.find("w: expected a number, got \"abcdefghijklmnopqrstuvwxyz0123456789abc...\"") != std::string::npos);
  m = message(R"({"fl_x": 300, "w": 64, "h": 48, "frames": [{"file_path": 7, "transform_matrix": []}]})");
  CHECK(m.find("frames[0].transform_matrix: expected 3 or 4 rows") != std::string::npos);
  m = message(R"({"fl_x": 300, "w": 64, "h": 48, "frames": [{"file_path": 7, "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]})");
  CHECK(m.find("frames[0].file_path: expected a string, got 7") != std::string::npos);
  m = message(R"({"fl_x": 300, "w": 64.5, "h": 48, "frames": [{)" + good + "}]}");
  CHECK(m.find("w: expected a whole number of pixels, got 64.5") != std::string::npos);
  m = message(R"({"frames": [1, 2)");
  CHECK(m.find("not valid JSON (line 1") != std::string::npos);
  CHECK(m.find("json.exception") == std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("a truncated image is found by the file check, before any stage runs, naming the file") {
  const fs::path dir = fs::temp_directory_path() / "nf_scene_truncated";
  fs::remove_all(dir);
  fs::create_directories(dir);
  Scene s;
  s.root = dir;
  s.cameras = ring();
  s.cameras.resize(2);
  for (auto& c : s.cameras) {
    c.image = dir / (c.name + ".png");
    write_png_file(c.image, kW, kH);
  }
  CHECK_NOTHROW(s.check_files("scene"));
  // The header is whole, so the size still reads; the data and the IEND chunk are gone.
  const std::string bytes = test::slurp(s.cameras[1].image);
  test::spit(s.cameras[1].image, bytes.substr(0, bytes.size() - 20));
  CHECK_THROWS_WITH_AS(s.check_files("scene"), doctest::Contains("camera 'cam1': image"), InputError);
  CHECK_THROWS_WITH_AS(s.check_files("scene"), doctest::Contains((s.cameras[1].image.string() + ": truncated PNG").c_str()),
                       InputError);
  // Cut inside the header (after the width and height, before the bit depth): nothing is read.
  test::spit(s.cameras[1].image, bytes.substr(0, 24));
  CHECK_THROWS_WITH_AS(s.check_files("scene"),
                       doctest::Contains((s.cameras[1].image.string() + ": truncated or corrupt PNG header").c_str()), InputError);
  fs::remove_all(dir);
}

TEST_CASE("JSON helpers: a matrix by rows, errors by path; untrusted text bounded in depth") {
  const json ok = json::parse(R"({"m": [[1, 0, 0, 5], [0, 2, 0, 6], [0, 0, 3, 7], [0, 0, 0, 1]]})");
  const glm::dmat4 m = io::matrix_rows(io::JsonField(ok, "frame.json").at("m"));
  CHECK(m[3][0] == 5.0);  // column-major: the translation column
  CHECK(m[1][1] == 2.0);
  const json short_row = json::parse(R"({"m": [[1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]})");
  CHECK_THROWS_WITH_AS(io::matrix_rows(io::JsonField(short_row, "frame.json").at("m")), doctest::Contains("frame.json: m[0]"), InputError);
  CHECK(io::parse_json_bounded("[[1]]", 4).has_value());
  CHECK_FALSE(io::parse_json_bounded(std::string(1000, '[') + std::string(1000, ']'), 32).has_value());
  CHECK_FALSE(io::parse_json_bounded("{not json", 32).has_value());
}

TEST_CASE("write_npz deflates members by default and stores them when asked; both read back exactly") {
  const fs::path file = fs::temp_directory_path() / "nf_test_members.npz";
  const std::vector<NpyWrite> arrays = {{"a", {2, 3}, "<f4", {1, 2, 3, 4, 5, 6.5}}, {"b", {4}, "<i4", {0, -1, 7, 1 << 20}}};
  for (const NpzMembers members : {NpzMembers::deflated, NpzMembers::stored}) {
    write_npz(file, arrays, members);
    CHECK(read_npz_array(file, "a").shape == std::vector<std::uint64_t>{2, 3});
    CHECK(read_npz_array(file, "a").values == arrays[0].values);
    CHECK(read_npz_array(file, "b").values == arrays[1].values);
    int error = 0;
    zip_t* z = zip_open(file.c_str(), ZIP_RDONLY, &error);
    REQUIRE(z != nullptr);
    zip_stat_t st;
    REQUIRE(zip_stat(z, "a.npy", 0, &st) == 0);
    CHECK(st.comp_method == (members == NpzMembers::stored ? ZIP_CM_STORE : ZIP_CM_DEFLATE));
    zip_close(z);
  }
  fs::remove(file);
}
