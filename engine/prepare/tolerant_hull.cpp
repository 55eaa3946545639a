#include "engine/prepare/tolerant_hull.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "engine/core/parallel.hpp"

namespace nf::prepare {

bool in_tolerant_hull(const std::vector<io::Camera>& cameras, const std::vector<glm::dmat4>& world_to_camera, const std::vector<cv::Mat>& masks,
                      const glm::dvec3& p, const std::vector<char>* left_out) {
  std::size_t misses = 0, seen = 0;
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    if (left_out && (*left_out)[i]) continue;
    const glm::dvec3 q = cameras[i].project(p, world_to_camera[i]);
    if (q.z <= 0 || q.x < 0 || q.y < 0 || q.x >= masks[i].cols || q.y >= masks[i].rows) continue;
    ++seen;
    misses += masks[i].at<std::uint8_t>(int(q.y), int(q.x)) == 0;
  }
  return seen >= 3 && misses <= std::max<std::size_t>(1, seen / 5);
}

HullGrid::HullGrid(const AnimalBox& b, std::uint32_t cells_on_longest_side) : box(b) {
  const glm::dvec3 extent = box.hi - box.lo;
  side = std::max({extent.x, extent.y, extent.z}) / double(std::max<std::uint32_t>(1, cells_on_longest_side));
  cells = glm::uvec3(glm::max(glm::dvec3(1.0), glm::ceil(extent / side)));
}

glm::dvec3 HullGrid::centre(std::size_t k) const {
  const glm::dvec3 at(double(k % cells.x), double((k / cells.x) % cells.y), double(k / (std::size_t(cells.x) * cells.y)));
  return box.world(box.lo + side * (at + 0.5));
}

std::optional<std::size_t> HullGrid::cell_of(const glm::dvec3& world) const {
  const glm::dvec3 cell = glm::floor((box.local(world) - box.lo) / side);
  if (!glm::all(glm::greaterThanEqual(cell, glm::dvec3(0.0))) || !glm::all(glm::lessThan(cell, glm::dvec3(cells)))) return std::nullopt;
  return index(std::size_t(cell.x), std::size_t(cell.y), std::size_t(cell.z));
}

std::vector<char> HullGrid::carve(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& masks, const std::vector<char>* left_out) const {
  std::vector<char> kept(total(), 0);
  std::vector<glm::dmat4> to_camera;
  for (const io::Camera& c : cameras) to_camera.push_back(c.world_to_camera());
  parallel_for(total(), [&](std::size_t k0, std::size_t k1) {
    for (std::size_t k = k0; k < k1; ++k) kept[k] = in_tolerant_hull(cameras, to_camera, masks, centre(k), left_out);
  });
  return kept;
}

cv::Mat draw_voxels(const io::Camera& c, const std::vector<glm::dvec3>& centres, double side, double radius_share, DiscRadius rounding) {
  cv::Mat out = cv::Mat::zeros(int(c.height), int(c.width), CV_8U);
  const glm::dmat4 to_camera = c.world_to_camera();
  for (const glm::dvec3& p : centres)
    if (const glm::dvec3 q = c.project(p, to_camera); q.z > 0) {
      const double r = radius_share * side * c.fx / q.z;
      const int radius = std::max(1, rounding == DiscRadius::rounded_up ? int(std::ceil(r)) : int(std::lround(r)));
      cv::circle(out, cv::Point(int(q.x), int(q.y)), radius, cv::Scalar(255), cv::FILLED);
    }
  return out;
}

double mask_iou(const cv::Mat& a, const cv::Mat& b) {
  const double either = double(cv::countNonZero(a | b));
  return either > 0 ? double(cv::countNonZero(a & b)) / either : 0.0;
}

}  // namespace nf::prepare
