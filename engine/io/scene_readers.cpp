// Camera formats other than transforms.json: NeuS (cameras_sphere.npz), Artemis (CamPose.inf +
// Intrinsic.inf) and COLMAP text models. Each converts to the OpenGL camera-to-world convention.
#include <algorithm>
#include <cmath>
#include <map>
#include <system_error>
#include <fstream>
#include <sstream>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/io/image_size.hpp"
#include "engine/io/npz.hpp"
#include "engine/io/scene.hpp"

namespace nf::io {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> images_in(const fs::path& folder) {
  std::vector<fs::path> files;
  if (!fs::is_directory(folder)) return files;
  for (const auto& e : fs::directory_iterator(folder)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".PNG" || ext == ".JPG") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// P = K [R | t] (3x4, rows) -> intrinsics and an OpenCV camera-to-world pose, by RQ decomposition.
void decompose_projection(const double P[3][4], Camera& c, const std::string& where) {
  glm::dvec3 m[3] = {{P[0][0], P[0][1], P[0][2]}, {P[1][0], P[1][1], P[1][2]}, {P[2][0], P[2][1], P[2][2]}};
  glm::dvec3 p4(P[0][3], P[1][3], P[2][3]);
  if (glm::determinant(glm::dmat3(m[0], m[1], m[2])) < 0) {  // P is defined up to scale, sign included
    for (auto& r : m) r = -r;
    p4 = -p4;
  }
  const double k33 = glm::length(m[2]);
  if (!(k33 > 0)) throw InputError(where + ": projection matrix is singular");
  const glm::dvec3 r3 = m[2] / k33;
  const double k23 = glm::dot(m[1], r3);
  const glm::dvec3 r2u = m[1] - k23 * r3;
  const double k22 = glm::length(r2u);
  const glm::dvec3 r2 = r2u / k22;
  const double k13 = glm::dot(m[0], r3), k12 = glm::dot(m[0], r2);
  const glm::dvec3 r1u = m[0] - k13 * r3 - k12 * r2;
  const double k11 = glm::length(r1u);
  const glm::dvec3 r1 = r1u / k11;
  if (!(k11 > 0 && k22 > 0)) throw InputError(where + ": projection matrix is singular");
  if (std::fabs(k12 / k11) > 1e-6) throw InputError(where + ": skewed intrinsics are not supported");
  c.fx = k11 / k33, c.fy = k22 / k33, c.cx = k13 / k33, c.cy = k23 / k33;
  // World-to-camera rotation R has rows r1, r2, r3 (glm is column-major: R^T has them as columns).
  // From K [R | t'] = P: t' = K^-1 p4, and the camera centre is C = -R^T t'.
  const glm::dmat3 K = glm::transpose(glm::dmat3(glm::dvec3(k11, k12, k13), glm::dvec3(0, k22, k23), glm::dvec3(0, 0, k33)));
  const glm::dvec3 t_prime = glm::inverse(K) * p4;
  const glm::dmat3 Rt(r1, r2, r3);  // columns r1, r2, r3: R^T, the camera's axes in world coordinates
  const glm::dvec3 center = -(Rt * t_prime);
  glm::dmat4 c2w(1.0);
  for (int col = 0; col < 3; ++col) c2w[col] = glm::dvec4(Rt[col], 0.0);
  c2w[3] = glm::dvec4(center, 1.0);
  c.camera_to_world = opencv_to_opengl(c2w);
}

}  // namespace

Scene read_neus_scene(const fs::path& folder) {
  const fs::path file = folder / "cameras_sphere.npz";
  if (!fs::exists(file)) throw InputError(folder.string() + ": no cameras_sphere.npz");
  const auto images = images_in(folder / "image"), masks = images_in(folder / "mask");
  if (images.empty()) throw InputError(folder.string() + ": no images in image/");
  if (!masks.empty() && masks.size() != images.size())
    throw InputError(folder.string() + ": " + std::to_string(masks.size()) + " masks for " + std::to_string(images.size()) + " images");
  Scene scene;
  scene.root = folder;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const std::string where = file.string() + ": world_mat_" + std::to_string(i);
    const NpyArray w = read_npz_array(file, "world_mat_" + std::to_string(i));
    // 3x4 or 4x4 (or the same flattened); rows of another length would be read across each other.
    const bool matrix = w.shape.size() == 2 && (w.shape[0] == 3 || w.shape[0] == 4) && w.shape[1] == 4;
    const bool flat = w.shape.size() == 1 && (w.values.size() == 12 || w.values.size() == 16);
    if (!matrix && !flat) throw InputError(where + " must be 3x4 or 4x4, found " + std::to_string(w.values.size()) + " values");
    double P[3][4];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) P[r][c] = w.values[std::size_t(r) * 4 + std::size_t(c)];
    Camera cam;
    decompose_projection(P, cam, where);
    cam.name = images[i].stem().string();
    cam.image = images[i];
    if (!masks.empty()) cam.mask = masks[i];
    std::tie(cam.width, cam.height) = image_size(images[i]);
    scene.cameras.push_back(cam);
  }
  scene.validate(file.string());
  return scene;
}

Scene read_artemis_scene(const fs::path& folder) {
  const std::string poses_file = (folder / "CamPose.inf").string(), intrinsics_file = (folder / "Intrinsic.inf").string();
  std::ifstream poses(poses_file), intrinsics(intrinsics_file);
  if (!poses) throw InputError(poses_file + ": cannot open");
  if (!intrinsics) throw InputError(intrinsics_file + ": cannot open");
  // Intrinsic.inf: per camera its index, then the 3x3 K row by row.
  std::vector<double> k_numbers;
  for (double v; intrinsics >> v;) k_numbers.push_back(v);
  if (k_numbers.size() % 10) throw InputError(intrinsics_file + ": expected blocks of an index and 9 numbers (K)");
  Scene scene;
  scene.root = folder;
  std::string line;
  std::size_t row = 0;
  while (std::getline(poses, line)) {
    std::istringstream words(line);
    std::vector<double> v;
    for (double x; words >> x;) v.push_back(x);
    if (v.empty()) continue;
    const std::string where = poses_file + ": row " + std::to_string(row);
    if (v.size() != 12) throw InputError(where + ": expected 12 numbers, found " + std::to_string(v.size()));
    if ((row + 1) * 10 > k_numbers.size()) throw InputError(intrinsics_file + ": no intrinsics for camera " + std::to_string(row));
    // Columns 0-2: the camera's z axis, 3-5: x, 6-8: y, 9-11: position (camera-to-world, OpenCV axes).
    glm::dmat4 c2w(1.0);
    c2w[2] = glm::dvec4(v[0], v[1], v[2], 0);
    c2w[0] = glm::dvec4(v[3], v[4], v[5], 0);
    c2w[1] = glm::dvec4(v[6], v[7], v[8], 0);
    c2w[3] = glm::dvec4(v[9], v[10], v[11], 1);
    Camera c;
    const double* K = &k_numbers[row * 10 + 1];
    c.fx = K[0], c.cx = K[2], c.fy = K[4], c.cy = K[5];
    c.camera_to_world = opencv_to_opengl(c2w);
    char name[32];
    std::snprintf(name, sizeof name, "img_%04zu", row);
    c.name = name;
    c.image = folder / (c.name + ".jpg");
    if (!fs::exists(c.image)) c.image = folder / (c.name + ".png");
    c.mask = folder / (c.name + "_alpha.png");
    if (!fs::exists(c.mask)) c.mask.clear();
    std::tie(c.width, c.height) = image_size(c.image);
    scene.cameras.push_back(c);
    ++row;
  }
  scene.validate(poses_file);
  return scene;
}

Scene read_colmap_scene(const fs::path& folder, const fs::path& masks, const fs::path& images_dir) {
  const std::string cameras_file = (folder / "cameras.txt").string(), images_file = (folder / "images.txt").string();
  std::ifstream cameras(cameras_file), images(images_file);
  if (!cameras) throw InputError(cameras_file + ": cannot open");
  if (!images) throw InputError(images_file + ": cannot open");
  struct Intrinsics {
    std::uint32_t w, h;
    double fx, fy, cx, cy;
  };
  std::map<long long, Intrinsics> intrinsics;
  std::string line;
  while (std::getline(cameras, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    long long id;
    std::string model;
    Intrinsics in{};
    words >> id >> model >> in.w >> in.h;
    std::vector<double> p;
    for (double x; words >> x;) p.push_back(x);
    const std::string where = cameras_file + ": camera " + std::to_string(id) + " (" + model + ")";
    const auto distortion_free = [&](std::size_t from) {
      for (std::size_t i = from; i < p.size(); ++i)
        if (p[i] != 0) throw InputError(where + ": lens distortion is not supported; undistort the images first (colmap image_undistorter)");
    };
    if (model == "SIMPLE_PINHOLE" && p.size() == 3) in.fx = in.fy = p[0], in.cx = p[1], in.cy = p[2];
    else if (model == "PINHOLE" && p.size() == 4) in.fx = p[0], in.fy = p[1], in.cx = p[2], in.cy = p[3];
    else if ((model == "SIMPLE_RADIAL" || model == "RADIAL") && p.size() >= 4) distortion_free(3), in.fx = in.fy = p[0], in.cx = p[1], in.cy = p[2];
    else if (model == "OPENCV" && p.size() == 8) distortion_free(4), in.fx = p[0], in.fy = p[1], in.cx = p[2], in.cy = p[3];
    else throw InputError(where + ": unsupported camera model or wrong parameter count");
    intrinsics[id] = in;
  }
  Scene scene;
  scene.root = folder;
  bool pose_line = true;
  while (std::getline(images, line)) {
    if (!line.empty() && line[0] == '#') continue;
    if (!pose_line) {  // the 2D points line that follows each image
      pose_line = true;
      continue;
    }
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream words(line);
    long long image_id, camera_id;
    double qw, qx, qy, qz, tx, ty, tz;
    std::string name;
    if (!(words >> image_id >> qw >> qx >> qy >> qz >> tx >> ty >> tz >> camera_id >> name))
      throw InputError(images_file + ": malformed image line '" + line + "'");
    pose_line = false;
    const auto it = intrinsics.find(camera_id);
    if (it == intrinsics.end()) throw InputError(images_file + ": image '" + name + "' uses unknown camera " + std::to_string(camera_id));
    // World-to-camera rotation from the unit quaternion, OpenCV axes.
    const double n = std::sqrt(qw * qw + qx * qx + qy * qy + qz * qz);
    qw /= n, qx /= n, qy /= n, qz /= n;
    const glm::dmat3 R = glm::transpose(glm::dmat3(
        glm::dvec3(1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)),
        glm::dvec3(2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)),
        glm::dvec3(2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy))));
    const glm::dmat3 Rt = glm::transpose(R);
    glm::dmat4 c2w(1.0);
    for (int col = 0; col < 3; ++col) c2w[col] = glm::dvec4(Rt[col], 0.0);
    c2w[3] = glm::dvec4(-(Rt * glm::dvec3(tx, ty, tz)), 1.0);
    Camera c;
    c.name = fs::path(name).stem().string();
    c.width = it->second.w, c.height = it->second.h;
    c.fx = it->second.fx, c.fy = it->second.fy, c.cx = it->second.cx, c.cy = it->second.cy;
    c.camera_to_world = opencv_to_opengl(c2w);
    c.image = (images_dir.empty() ? folder / "images" : images_dir) / name;
    if (!masks.empty()) c.mask = masks / (c.name + ".png");
    scene.cameras.push_back(c);
  }
  scene.validate(images_file);
  return scene;
}

namespace {

Scene read_scene_format(const fs::path& path) {
  if (fs::is_regular_file(path) && path.extension() == ".json") return read_transforms_json(path);
  if (fs::exists(path / "transforms.json")) return read_transforms_json(path / "transforms.json");
  if (fs::exists(path / "cameras_sphere.npz")) return read_neus_scene(path);
  if (fs::exists(path / "CamPose.inf")) return read_artemis_scene(path);
  if (fs::exists(path / "cameras.txt")) return read_colmap_scene(path, fs::exists(path / "masks") ? path / "masks" : fs::path());
  if (fs::exists(path / "sparse" / "0" / "cameras.txt"))
    return read_colmap_scene(path / "sparse" / "0", fs::exists(path / "masks") ? path / "masks" : fs::path(), path / "images");  // COLMAP's project layout
  throw InputError(path.string() + ": no scene found (transforms.json, cameras_sphere.npz, CamPose.inf or COLMAP cameras.txt)");
}

}  // namespace

Scene read_scene(const fs::path& path) {
  Scene scene = read_scene_format(path);
  // Photos cut out with an alpha channel (NeRF-style RGBA PNGs) and no mask file: the alpha is the
  // mask (mask_of reads the last of 2 or 4 channels).
  std::size_t from_alpha = 0;
  for (Camera& c : scene.cameras)
    if (std::error_code ec; c.mask.empty() && fs::exists(c.image, ec)) {  // a bad name is reported by check_files
      const std::string ext = c.image.extension().string();
      if (ext != ".png" && ext != ".PNG") continue;
      const std::uint32_t channels = image_channels(c.image);
      if (channels == 2 || channels == 4) c.mask = c.image, ++from_alpha;
    }
  if (from_alpha) log::info(path.string(), ": ", from_alpha, " camera(s) without a mask use their image's alpha channel as the mask");
  return scene;
}

}  // namespace nf::io
