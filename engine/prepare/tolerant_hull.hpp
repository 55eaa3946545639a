#pragma once
// The visual hull prepare carves from masks, tolerant of a few wrong ones: a point lies in it when
// at least 3 views see it and all but a fifth of them (at least one may miss) see it inside their
// masks; and the IoU the masks are compared by. Shared by the automatic masks and the pose check;
// nf_prepare's own (OpenCV) header.
#include <algorithm>
#include <vector>

#include <glm/glm.hpp>
#include <opencv2/core.hpp>

#include "engine/io/scene.hpp"

namespace nf::prepare {

// `masks`: per camera, CV_8U, non-zero inside; `left_out` (when given): views that take no part.
inline bool in_tolerant_hull(const std::vector<io::Camera>& cameras, const std::vector<cv::Mat>& masks, const glm::dvec3& p,
                             const std::vector<char>* left_out = nullptr) {
  std::size_t misses = 0, seen = 0;
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    if (left_out && (*left_out)[i]) continue;
    const glm::dvec3 q = cameras[i].project(p);
    if (q.z <= 0 || q.x < 0 || q.y < 0 || q.x >= masks[i].cols || q.y >= masks[i].rows) continue;
    ++seen;
    misses += masks[i].at<std::uint8_t>(int(q.y), int(q.x)) == 0;
  }
  return seen >= 3 && misses <= std::max<std::size_t>(1, seen / 5);
}

// The IoU of two CV_8U masks (non-zero inside); 0 when both are empty.
inline double mask_iou(const cv::Mat& a, const cv::Mat& b) {
  const double either = double(cv::countNonZero(a | b));
  return either > 0 ? double(cv::countNonZero(a & b)) / either : 0.0;
}

}  // namespace nf::prepare
