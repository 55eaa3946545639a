// Camera formats: transforms.json round-trips; NeuS, Artemis and COLMAP fixtures written from the
// same cameras agree with it to 1e-5 (intrinsics, poses and projected points); distortion and bad
// input are refused with the file and field named.
#include <doctest/doctest.h>

#include <zip.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/io/scene.hpp"

using namespace nf;
using namespace nf::io;
namespace fs = std::filesystem;

namespace {

const std::uint32_t kW = 320, kH = 240;

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

void write_png_header(const fs::path& p, std::uint32_t w, std::uint32_t h) {
  unsigned char b[24] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R'};
  for (int i = 0; i < 4; ++i) b[16 + i] = std::uint8_t(w >> (24 - 8 * i)), b[20 + i] = std::uint8_t(h >> (24 - 8 * i));
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<char*>(b), 24);
}

void write_jpeg_header(const fs::path& p, std::uint32_t w, std::uint32_t h) {
  const unsigned char b[] = {0xff, 0xd8, 0xff, 0xc0, 0, 17, 8, std::uint8_t(h >> 8), std::uint8_t(h), std::uint8_t(w >> 8),
                             std::uint8_t(w), 3, 1, 0x22, 0, 2, 0x11, 1, 3, 0x11, 1};
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(b), sizeof b);
}

// OpenCV world-to-camera rotation (rows) and translation of a camera.
void opencv_extrinsics(const Camera& c, double R[3][3], double t[3]) {
  glm::dmat4 flip(1.0);
  flip[1][1] = flip[2][2] = -1.0;
  const glm::dmat4 w2c = glm::inverse(c.camera_to_world * flip);
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) R[r][k] = w2c[k][r];
    t[r] = w2c[3][r];
  }
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

void add_npy(zip_t* z, const std::string& name, const double m[16], std::vector<std::string>& keep) {
  std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (4, 4), }";
  while ((10 + header.size() + 1) % 64) header += ' ';
  header += '\n';
  std::string blob = std::string("\x93NUMPY\x01\x00", 8);
  blob += char(header.size() & 0xff);
  blob += char(header.size() >> 8);
  blob += header;
  blob.append(reinterpret_cast<const char*>(m), 16 * sizeof(double));
  keep.push_back(blob);
  zip_source_t* src = zip_source_buffer(z, keep.back().data(), keep.back().size(), 0);
  REQUIRE(zip_file_add(z, (name + ".npy").c_str(), src, ZIP_FL_OVERWRITE) >= 0);
}

}  // namespace

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
    int error = 0;
    zip_t* z = zip_open((root / "cameras_sphere.npz").c_str(), ZIP_CREATE | ZIP_TRUNCATE, &error);
    REQUIRE(z);
    std::vector<std::string> keep;
    keep.reserve(64);
    for (std::size_t i = 0; i < cams.size(); ++i) {
      double R[3][3], t[3];
      opencv_extrinsics(cams[i], R, t);
      const double K[3][3] = {{cams[i].fx, 0, cams[i].cx}, {0, cams[i].fy, cams[i].cy}, {0, 0, 1}};
      double P[16] = {0};
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) {
          double v = 0;
          for (int k = 0; k < 3; ++k) v += K[r][k] * (c < 3 ? R[k][c] : t[k]);
          P[r * 4 + c] = 2.0 * v;  // any scale: P is defined up to one
        }
      P[15] = 2.0;
      const double I[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
      add_npy(z, "world_mat_" + std::to_string(i), P, keep);
      add_npy(z, "scale_mat_" + std::to_string(i), I, keep);
      char name[32];
      std::snprintf(name, sizeof name, "%03u.png", unsigned(i));
      write_png_header(root / "image" / name, kW, kH);
      write_png_header(root / "mask" / name, kW, kH);
    }
    REQUIRE(zip_close(z) == 0);
    check_same(read_scene(root), cams);
  }

  SUBCASE("Artemis CamPose.inf and Intrinsic.inf") {
    fs::create_directories(root);
    std::ofstream poses(root / "CamPose.inf"), intrinsics(root / "Intrinsic.inf");
    poses.precision(17);
    intrinsics.precision(17);
    for (std::size_t i = 0; i < cams.size(); ++i) {
      glm::dmat4 flip(1.0);
      flip[1][1] = flip[2][2] = -1.0;
      const glm::dmat4 cv = cams[i].camera_to_world * flip;  // OpenCV camera-to-world
      for (int col : {2, 0, 1, 3}) poses << cv[col][0] << ' ' << cv[col][1] << ' ' << cv[col][2] << ' ';
      poses << '\n';
      intrinsics << i << '\n' << cams[i].fx << " 0 " << cams[i].cx << '\n' << "0 " << cams[i].fy << ' ' << cams[i].cy << "\n0 0 1\n\n";
      char name[32];
      std::snprintf(name, sizeof name, "img_%04u", unsigned(i));
      write_jpeg_header(root / (std::string(name) + ".jpg"), kW, kH);
      write_png_header(root / (std::string(name) + "_alpha.png"), kW, kH);
    }
    poses.close();
    intrinsics.close();
    const Scene s = read_scene(root);
    check_same(s, cams);
    CHECK(s.cameras[0].mask.filename() == "img_0000_alpha.png");
  }

  SUBCASE("COLMAP text model") {
    fs::create_directories(root);
    std::ofstream cameras(root / "cameras.txt"), images(root / "images.txt");
    cameras.precision(17);
    images.precision(17);
    cameras << "# Camera list\n";
    images << "# Image list\n";
    for (std::size_t i = 0; i < cams.size(); ++i) {
      cameras << i + 1 << " PINHOLE " << kW << ' ' << kH << ' ' << cams[i].fx << ' ' << cams[i].fy << ' ' << cams[i].cx
              << ' ' << cams[i].cy << '\n';
      double R[3][3], t[3];
      opencv_extrinsics(cams[i], R, t);
      // Rotation matrix -> unit quaternion (w, x, y, z).
      double q[4];
      const double tr = R[0][0] + R[1][1] + R[2][2];
      if (tr > 0) {
        const double s = 2 * std::sqrt(tr + 1);
        q[0] = s / 4, q[1] = (R[2][1] - R[1][2]) / s, q[2] = (R[0][2] - R[2][0]) / s, q[3] = (R[1][0] - R[0][1]) / s;
      } else if (R[0][0] > R[1][1] && R[0][0] > R[2][2]) {
        const double s = 2 * std::sqrt(1 + R[0][0] - R[1][1] - R[2][2]);
        q[0] = (R[2][1] - R[1][2]) / s, q[1] = s / 4, q[2] = (R[0][1] + R[1][0]) / s, q[3] = (R[0][2] + R[2][0]) / s;
      } else if (R[1][1] > R[2][2]) {
        const double s = 2 * std::sqrt(1 + R[1][1] - R[0][0] - R[2][2]);
        q[0] = (R[0][2] - R[2][0]) / s, q[1] = (R[0][1] + R[1][0]) / s, q[2] = s / 4, q[3] = (R[1][2] + R[2][1]) / s;
      } else {
        const double s = 2 * std::sqrt(1 + R[2][2] - R[0][0] - R[1][1]);
        q[0] = (R[1][0] - R[0][1]) / s, q[1] = (R[0][2] + R[2][0]) / s, q[2] = (R[1][2] + R[2][1]) / s, q[3] = s / 4;
      }
      images << i + 1 << ' ' << q[0] << ' ' << q[1] << ' ' << q[2] << ' ' << q[3] << ' ' << t[0] << ' ' << t[1] << ' '
             << t[2] << ' ' << i + 1 << ' ' << cams[i].name << ".png\n\n";
    }
    cameras.close();
    images.close();
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
