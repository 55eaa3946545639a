#pragma once
// The visual hull prepare carves from masks, tolerant of a few wrong ones: a point lies in it when
// at least 3 views see it and all but a fifth of them (at least one may miss) see it inside their
// masks; the voxel grid it is carved on (the animal's box, scene_layout.hpp), the hull drawn back
// into a view, and the IoU the masks are compared by. Shared by the automatic masks and the pose
// check; nf_prepare's own (OpenCV) header.
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>
#include <opencv2/core.hpp>

#include "engine/io/scene.hpp"
#include "engine/prepare/scene_layout.hpp"

namespace nf::prepare {

// `masks`: per camera, CV_8U, non-zero inside; `world_to_camera`: per camera, its world_to_camera();
// `left_out` (when given): views that take no part.
bool in_tolerant_hull(const std::vector<io::Camera>& cameras, const std::vector<glm::dmat4>& world_to_camera, const std::vector<cv::Mat>& masks,
                      const glm::dvec3& p, const std::vector<char>* left_out = nullptr);

// Cubic voxels over the animal's box, `cells` along its longest side (x fastest, then y, then z).
struct HullGrid {
  HullGrid(const AnimalBox& box, std::uint32_t cells_on_longest_side);
  AnimalBox box;
  double side = 0;  // a voxel's edge, scene units
  glm::uvec3 cells{1};
  std::size_t total() const { return std::size_t(cells.x) * cells.y * cells.z; }
  std::size_t index(std::size_t x, std::size_t y, std::size_t z) const { return (z * cells.y + y) * cells.x + x; }
  glm::dvec3 centre(std::size_t k) const;                             // world
  std::optional<std::size_t> cell_of(const glm::dvec3& world) const;  // none outside the box
  // Per voxel, whether its centre lies in the tolerant hull of `masks`.
  std::vector<char> carve(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& masks, const std::vector<char>* left_out = nullptr) const;
};

// Voxel centres drawn into a camera's frame as filled discs of `radius_share` x the voxel's edge
// (at least a pixel), their radius rounded up or to the nearest pixel: CV_8U, 255 inside.
enum class DiscRadius { rounded_up, rounded };
cv::Mat draw_voxels(const io::Camera& camera, const std::vector<glm::dvec3>& centres, double side, double radius_share, DiscRadius rounding);

// The IoU of two CV_8U masks (non-zero inside); 0 when both are empty.
double mask_iou(const cv::Mat& a, const cv::Mat& b);

}  // namespace nf::prepare
