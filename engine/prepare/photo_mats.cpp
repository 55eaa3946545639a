#include "engine/prepare/photo_mats.hpp"

#include <algorithm>

#include <opencv2/imgproc.hpp>

#include "engine/core/error.hpp"
#include "engine/io/image.hpp"

namespace nf::prepare {

cv::Mat photo_bgr(const io::Camera& camera) {
  const io::Image image = io::read_image(camera.image);
  if (image.width < camera.width || image.height < camera.height)
    throw InputError(camera.image.string() + ": " + std::to_string(image.width) + "x" + std::to_string(image.height) + " pixels, fewer than camera '" +
                     camera.name + "''s " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  cv::Mat bgr(int(image.height), int(image.width), CV_8UC3);
  for (std::uint32_t y = 0; y < image.height; ++y)
    for (std::uint32_t x = 0; x < image.width; ++x) {
      cv::Vec3b& px = bgr.at<cv::Vec3b>(int(y), int(x));
      for (int c = 0; c < 3; ++c) {
        const float v = image.at(x, y, std::min<std::uint32_t>(std::uint32_t(c), image.channels - 1));
        px[2 - c] = std::uint8_t(std::clamp(v, 0.f, 1.f) * 255.f + 0.5f);
      }
    }
  if (image.width == camera.width && image.height == camera.height) return bgr;
  cv::Mat reduced;  // a reduced camera (io::reduced_to): each pixel the mean of those it covers
  cv::resize(bgr, reduced, cv::Size(int(camera.width), int(camera.height)), 0, 0, cv::INTER_AREA);
  return reduced;
}

cv::Mat grey_levels(const cv::Mat& bgr) {
  cv::Mat g, out;
  cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
  g.convertTo(out, CV_32F);
  return out;
}

}  // namespace nf::prepare
