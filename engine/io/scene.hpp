#pragma once
// A multi-view scene: per camera, pinhole intrinsics, the camera-to-world pose in the OpenGL
// convention (x right, y up, the camera looks down -z) and where its image and mask are.
// Readers for the formats users have (nerfstudio / instant-ngp transforms.json, NeuS
// cameras_sphere.npz, Artemis CamPose.inf, COLMAP text models) all produce this; images are opened
// lazily by the stages that need them.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace nf::io {

struct Camera {
  std::string name;
  std::uint32_t width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  glm::dmat4 camera_to_world{1.0};  // OpenGL axes
  std::filesystem::path image, mask;  // may be empty

  // Pixel coordinates (x right, y down, origin at the top-left corner) of a world point, and its
  // depth along the viewing direction (positive in front of the camera).
  glm::dvec3 project(const glm::dvec3& world) const;
  // The same through a given world_to_camera(): project() inverts the pose on every call, so a loop
  // that projects many points through one camera inverts it once (the same result, bit for bit).
  glm::dvec3 project(const glm::dvec3& world, const glm::dmat4& world_to_camera) const;
  glm::dmat4 world_to_camera() const { return glm::inverse(camera_to_world); }
  // Its inverse: the world point at `depth` along the viewing direction behind pixel coordinates.
  glm::dvec3 unproject(const glm::dvec2& pixel, double depth) const;
  // The camera's centre (world).
  glm::dvec3 centre() const { return glm::dvec3(camera_to_world[3]); }
};

// The camera's projection onto its photo scaled by (sx, sy) and cropped: (x0, y0) the crop's corner
// at the new scale, width x height its size. Pixel coordinates have their origin at the photo's
// corner, so the principal point scales as the focal length does.
Camera scaled_crop(const Camera& camera, double sx, double sy, std::uint32_t x0, std::uint32_t y0, std::uint32_t width, std::uint32_t height);
// The whole photo reduced so that its longer side is at most `max_side` pixels (the camera itself
// when it is that small already).
Camera reduced_to(const Camera& camera, std::uint32_t max_side);

struct Scene {
  std::filesystem::path root;
  std::vector<Camera> cameras;
  std::optional<double> cm_per_unit;  // when the file declares metric units
  // Throws InputError naming the file and the camera and field that are wrong.
  void validate(const std::string& source) const;
  // Every camera's image (and mask, when it has one) exists, has the camera's size and is complete
  // (not truncated). Throws InputError naming the file, the camera and what is wrong. Reads a PNG's
  // or JPEG's header and last bytes only; EXR files are decoded.
  void check_files(const std::string& source) const;
};

Scene read_transforms_json(const std::filesystem::path& file);
void write_transforms_json(const std::filesystem::path& file, const Scene& scene);
Scene read_neus_scene(const std::filesystem::path& folder);      // cameras_sphere.npz, image/, mask/
Scene read_artemis_scene(const std::filesystem::path& folder);   // CamPose.inf, Intrinsic.inf, img_XXXX.jpg
// cameras.txt and images.txt in `folder`; the photos in `images` (default: folder/images).
Scene read_colmap_scene(const std::filesystem::path& folder, const std::filesystem::path& masks = {}, const std::filesystem::path& images = {});

// A folder in any of the formats above (or a transforms.json file).
Scene read_scene(const std::filesystem::path& path);

// The cameras a `--views` argument names: "all", or indices like "0,5,9" (duplicates dropped,
// order kept). Throws UsageError naming the bad entry or the valid range.
std::vector<std::uint32_t> parse_view_list(const std::string& views, std::size_t camera_count);

// OpenCV camera axes (x right, y down, z forward) <-> OpenGL (x right, y up, -z forward).
glm::dmat4 opencv_to_opengl(const glm::dmat4& camera_to_world_cv);

}  // namespace nf::io
