#include "engine/io/scene.hpp"

#include <algorithm>
#include <cmath>
#include <system_error>
#include <tuple>

#include "engine/core/error.hpp"
#include "engine/io/image.hpp"
#include "engine/io/image_size.hpp"

namespace nf::io {

glm::dvec3 Camera::project(const glm::dvec3& world) const { return project(world, world_to_camera()); }

glm::dvec3 Camera::project(const glm::dvec3& world, const glm::dmat4& to_camera) const {
  const glm::dvec4 c = to_camera * glm::dvec4(world, 1.0);
  const double depth = -c.z;  // OpenGL: the camera looks down -z
  return {cx + fx * c.x / depth, cy - fy * c.y / depth, depth};
}

glm::dvec3 Camera::unproject(const glm::dvec2& pixel, double depth) const {
  const glm::dvec3 in_camera((pixel.x - cx) / fx, -(pixel.y - cy) / fy, -1.0);  // OpenGL: the camera looks down -z
  return glm::dvec3(camera_to_world * glm::dvec4(in_camera * depth, 1.0));
}

Camera scaled_crop(const Camera& camera, double sx, double sy, std::uint32_t x0, std::uint32_t y0, std::uint32_t width, std::uint32_t height) {
  Camera c = camera;
  c.fx = camera.fx * sx, c.fy = camera.fy * sy;
  c.cx = camera.cx * sx - double(x0), c.cy = camera.cy * sy - double(y0);
  c.width = width, c.height = height;
  return c;
}

Camera reduced_to(const Camera& camera, std::uint32_t max_side) {
  const double s = std::min(1.0, double(max_side) / double(std::max(camera.width, camera.height)));
  if (s >= 1.0) return camera;
  const auto w = std::max<std::uint32_t>(1, std::uint32_t(std::lround(camera.width * s)));
  const auto h = std::max<std::uint32_t>(1, std::uint32_t(std::lround(camera.height * s)));
  return scaled_crop(camera, double(w) / camera.width, double(h) / camera.height, 0, 0, w, h);
}

glm::dmat4 opencv_to_opengl(const glm::dmat4& c2w) {
  glm::dmat4 flip(1.0);
  flip[1][1] = -1.0;
  flip[2][2] = -1.0;
  return c2w * flip;
}

void Scene::validate(const std::string& source) const {
  if (cameras.empty()) throw InputError(source + ": no cameras");
  for (const Camera& c : cameras) {
    const std::string where = source + ": camera '" + c.name + "'";
    if (c.width == 0 || c.height == 0 || c.width > 65536 || c.height > 65536)
      throw InputError(where + ": image size " + std::to_string(c.width) + "x" + std::to_string(c.height) + " is invalid");
    for (double v : {c.fx, c.fy, c.cx, c.cy})
      if (!std::isfinite(v)) throw InputError(where + ": intrinsics are not finite");
    if (!(c.fx > 0) || !(c.fy > 0)) throw InputError(where + ": focal lengths must be positive");
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        if (!std::isfinite(c.camera_to_world[i][j])) throw InputError(where + ": pose is not finite");
    const glm::dmat3 r(c.camera_to_world);
    const glm::dmat3 rrt = r * glm::transpose(r);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (std::fabs(rrt[i][j] - (i == j ? 1.0 : 0.0)) > 1e-3)
          throw InputError(where + ": the pose's rotation is not orthonormal (scaled or sheared transform)");
  }
}

void Scene::check_files(const std::string& source) const {
  for (const Camera& c : cameras) {
    const std::string where = source + ": camera '" + c.name + "'";
    auto check = [&](const std::filesystem::path& file, const char* field) {
      std::error_code ec;  // a name the file system refuses (too long, not a path) is a bad input, not a crash
      if (!std::filesystem::exists(file, ec))
        throw InputError(where + ": " + field + " " + file.string() + (ec ? " cannot be read: " + ec.message() : " does not exist"));
      const std::string ext = file.extension().string();
      std::uint32_t w = 0, h = 0;
      try {
        if (ext == ".exr" || ext == ".EXR") {
          const Image image = read_image(file);
          w = image.width, h = image.height;
        } else {
          // Header and last bytes only: a file cut short is found here, before any stage runs, not
          // when a stage decodes it (stb decodes a truncated JPEG without an error).
          std::tie(w, h) = image_size(file);
          require_complete_image(file);
        }
      } catch (const InputError& e) {
        throw InputError(where + ": " + field + " " + e.what());  // e.what() starts with the file
      }
      if (w != c.width || h != c.height)
        throw InputError(where + ": " + field + " " + file.string() + " is " + std::to_string(w) + "x" + std::to_string(h) +
                         " but the camera is " + std::to_string(c.width) + "x" + std::to_string(c.height));
    };
    if (c.image.empty()) throw InputError(where + ": no image path");
    check(c.image, "image");
    if (!c.mask.empty()) check(c.mask, "mask");
  }
}

std::vector<std::uint32_t> parse_view_list(const std::string& views, std::size_t camera_count) {
  std::vector<std::uint32_t> out;
  if (views == "all") {
    for (std::size_t i = 0; i < camera_count; ++i) out.push_back(std::uint32_t(i));
    return out;
  }
  std::size_t start = 0;
  while (start <= views.size()) {
    const std::size_t comma = std::min(views.find(',', start), views.size());
    std::string item = views.substr(start, comma - start);
    item.erase(0, item.find_first_not_of(' '));
    item.erase(item.find_last_not_of(' ') + 1);
    if (item.empty() || item.find_first_not_of("0123456789") != std::string::npos || item.size() > 9)
      throw UsageError("--views: '" + item + "' is not a camera index (give 'all' or indices like 0,5,9)");
    const std::uint64_t index = std::stoull(item);
    if (index >= camera_count)
      throw UsageError("--views: camera index " + item + " is out of range; the scene has " +
                       std::to_string(camera_count) + " cameras (0.." + std::to_string(camera_count - 1) + ")");
    if (std::find(out.begin(), out.end(), std::uint32_t(index)) == out.end()) out.push_back(std::uint32_t(index));
    start = comma + 1;
  }
  return out;
}

}  // namespace nf::io
