#pragma once
// Camera files in the NeuS, Artemis and COLMAP formats written from a list of cameras, so tests can
// check that each reader gives back the same cameras (and projects points the same way). Images
// are the caller's business; the PNG/JPEG header writers make stand-ins the readers can size.
#include <doctest/doctest.h>
#include <zip.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "engine/io/scene.hpp"

namespace nf::test {

inline void write_jpeg_header(const std::filesystem::path& p, std::uint32_t w, std::uint32_t h) {
  const unsigned char b[] = {0xff, 0xd8, 0xff, 0xc0, 0, 17, 8, std::uint8_t(h >> 8), std::uint8_t(h), std::uint8_t(w >> 8),
                             std::uint8_t(w), 3, 1, 0x22, 0, 2, 0x11, 1, 3, 0x11, 1};
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(b), sizeof b);
}

// Camera-to-world (OpenGL axes: the camera looks down -z) of a camera at `eye` looking at `target`.
inline glm::dmat4 look_at(glm::dvec3 eye, glm::dvec3 target, glm::dvec3 up = {0, 1, 0}) {
  const glm::dvec3 z = glm::normalize(eye - target);
  glm::dvec3 x = glm::cross(up, z);
  if (glm::length(x) < 1e-9) x = glm::cross(glm::dvec3(1, 0, 0), z);
  x = glm::normalize(x);
  const glm::dvec3 y = glm::cross(z, x);
  glm::dmat4 m(1.0);
  m[0] = glm::dvec4(x, 0), m[1] = glm::dvec4(y, 0), m[2] = glm::dvec4(z, 0), m[3] = glm::dvec4(eye, 1);
  return m;
}

// A pinhole camera of w x h pixels, square pixels, horizontal field of view fov_deg, centred
// principal point.
inline io::Camera pinhole_camera(const std::string& name, const glm::dmat4& camera_to_world, std::uint32_t w,
                                 std::uint32_t h, double fov_deg) {
  io::Camera c;
  c.name = name;
  c.width = w, c.height = h;
  c.fx = c.fy = 0.5 * w / std::tan(0.5 * fov_deg * 3.14159265358979323846 / 180.0);
  c.cx = 0.5 * w, c.cy = 0.5 * h;
  c.camera_to_world = camera_to_world;
  return c;
}

// OpenCV world-to-camera rotation (rows) and translation of a camera.
inline void opencv_extrinsics(const io::Camera& c, double R[3][3], double t[3]) {
  glm::dmat4 flip(1.0);
  flip[1][1] = flip[2][2] = -1.0;
  const glm::dmat4 w2c = glm::inverse(c.camera_to_world * flip);
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) R[r][k] = w2c[k][r];
    t[r] = w2c[3][r];
  }
}

inline void add_npy(zip_t* z, const std::string& name, const double m[16], std::vector<std::string>& keep) {
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

// root/cameras_sphere.npz with world_mat_i = 2 K [R|t] (any scale) and identity scale_mat_i.
inline void write_neus_cameras(const std::filesystem::path& root, const std::vector<io::Camera>& cams) {
  int error = 0;
  zip_t* z = zip_open((root / "cameras_sphere.npz").c_str(), ZIP_CREATE | ZIP_TRUNCATE, &error);
  REQUIRE(z);
  std::vector<std::string> keep;
  keep.reserve(2 * cams.size() + 1);
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
  }
  REQUIRE(zip_close(z) == 0);
}

// root/CamPose.inf (columns 0-2 -> R[:,2], 3-5 -> R[:,0], 6-8 -> R[:,1], 9-11 -> t, OpenCV
// camera-to-world) and root/Intrinsic.inf.
inline void write_artemis_cameras(const std::filesystem::path& root, const std::vector<io::Camera>& cams) {
  std::ofstream poses(root / "CamPose.inf"), intrinsics(root / "Intrinsic.inf");
  poses.precision(17);
  intrinsics.precision(17);
  for (std::size_t i = 0; i < cams.size(); ++i) {
    glm::dmat4 flip(1.0);
    flip[1][1] = flip[2][2] = -1.0;
    const glm::dmat4 cv = cams[i].camera_to_world * flip;
    for (int col : {2, 0, 1, 3}) poses << cv[col][0] << ' ' << cv[col][1] << ' ' << cv[col][2] << ' ';
    poses << '\n';
    intrinsics << i << '\n' << cams[i].fx << " 0 " << cams[i].cx << '\n' << "0 " << cams[i].fy << ' ' << cams[i].cy << "\n0 0 1\n\n";
  }
}

// Artemis image names for view i: img_XXXX.jpg and its mask img_XXXX_alpha.png.
inline std::string artemis_name(std::size_t i) {
  char name[32];
  std::snprintf(name, sizeof name, "img_%04u", unsigned(i));
  return name;
}

// root/cameras.txt (PINHOLE) and root/images.txt (quaternion + translation, image <name>.png).
inline void write_colmap_cameras(const std::filesystem::path& root, const std::vector<io::Camera>& cams) {
  std::ofstream cameras(root / "cameras.txt"), images(root / "images.txt");
  cameras.precision(17);
  images.precision(17);
  cameras << "# Camera list\n";
  images << "# Image list\n";
  for (std::size_t i = 0; i < cams.size(); ++i) {
    cameras << i + 1 << " PINHOLE " << cams[i].width << ' ' << cams[i].height << ' ' << cams[i].fx << ' ' << cams[i].fy << ' '
            << cams[i].cx << ' ' << cams[i].cy << '\n';
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
    images << i + 1 << ' ' << q[0] << ' ' << q[1] << ' ' << q[2] << ' ' << q[3] << ' ' << t[0] << ' ' << t[1] << ' ' << t[2]
           << ' ' << i + 1 << ' ' << cams[i].name << ".png\n\n";
  }
}

}  // namespace nf::test
