#pragma once
// A camera's photo as the OpenCV images prepare's masks and floor checks work on: 8-bit BGR (what
// GrabCut takes) and its grey levels as floats, 0-255 (what the floor's patch correlation takes).
#include <cstdint>

#include <opencv2/core.hpp>

#include "engine/io/scene.hpp"

namespace nf::prepare {

// The longer side, in pixels, of the reduced copies of the photos prepare's image checks (the
// automatic masks' cuts, the floor's evidence) work on: a phone's 12 MP photo then costs what a
// 1,024 px one does, in time and memory.
constexpr std::uint32_t kWorkingSide = 1024;

// The photo at the camera's size: reduced (INTER_AREA) when the camera is a reduced copy of the
// photo's (io::reduced_to). InputError when the photo is smaller than the camera.
cv::Mat photo_bgr(const io::Camera& camera);
cv::Mat grey_levels(const cv::Mat& bgr);  // CV_32F

}  // namespace nf::prepare
