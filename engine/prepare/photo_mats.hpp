#pragma once
// A camera's photo as the OpenCV images prepare's masks and floor checks work on: 8-bit BGR (what
// GrabCut takes) and its grey levels as floats, 0-255 (what the floor's patch correlation takes).
#include <opencv2/core.hpp>

#include "engine/io/scene.hpp"

namespace nf::prepare {

cv::Mat photo_bgr(const io::Camera& camera);
cv::Mat grey_levels(const cv::Mat& bgr);  // CV_32F

}  // namespace nf::prepare
