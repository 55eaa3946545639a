#include "engine/orient/orientation_scales.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/error.hpp"

namespace nf::orient {

OrientationSums::OrientationSums(const OrientationMap& map) : stride_(std::size_t(map.orientation.width) + 1) {
  const std::uint32_t W = map.orientation.width, H = map.orientation.height;
  const std::size_t S = stride_;
  x_.assign(S * (H + 1), 0.0), y_.assign(x_.size(), 0.0), c_.assign(x_.size(), 0.0);
  for (std::uint32_t y = 0; y < H; ++y)
    for (std::uint32_t x = 0; x < W; ++x) {
      const std::size_t i = std::size_t(y) * W + x, at = (y + 1) * S + x + 1;
      const double a = map.orientation.pixels[i], c = map.confidence.pixels[i];
      x_[at] = c * std::cos(2 * a) + x_[at - 1] + x_[at - S] - x_[at - S - 1];
      y_[at] = c * std::sin(2 * a) + y_[at - 1] + y_[at - S] - y_[at - S - 1];
      c_[at] = c + c_[at - 1] + c_[at - S] - c_[at - S - 1];
    }
}

double OrientationSums::box(const std::vector<double>& t, std::uint32_t x0, std::uint32_t y0, std::uint32_t x1, std::uint32_t y1) const {
  return t[y1 * stride_ + x1] - t[y0 * stride_ + x1] - t[y1 * stride_ + x0] + t[y0 * stride_ + x0];
}

double OrientationSums::reliability(std::uint32_t x0, std::uint32_t y0, std::uint32_t x1, std::uint32_t y1) const {
  const double c = box(c_, x0, y0, x1, y1);
  const double noise = 2.0 / std::sqrt(double(x1 - x0) * double(y1 - y0));
  if (!(c > 0) || !(noise < 1)) return 0.0;
  const double coherence = std::hypot(box(x_, x0, y0, x1, y1), box(y_, x0, y0, x1, y1)) / c;
  return std::clamp((coherence - noise) / (1.0 - noise), 0.0, 1.0);
}

std::vector<float> orientation_reliability(const OrientationMap& map, std::uint32_t window) {
  const std::uint32_t W = map.orientation.width, H = map.orientation.height, half = window / 2;
  const OrientationSums sums(map);
  std::vector<float> out(std::size_t(W) * H, 0.f);
  for (std::uint32_t y = 0; y < H; ++y)
    for (std::uint32_t x = 0; x < W; ++x)
      out[std::size_t(y) * W + x] = float(sums.reliability(x > half ? x - half : 0, y > half ? y - half : 0, std::min(W, x + half + 1),
                                                             std::min(H, y + half + 1)));
  return out;
}

io::Image halve(const io::Image& image) {
  io::Image h{(image.width + 1) / 2, (image.height + 1) / 2, image.channels, {}};
  h.pixels.assign(std::size_t(h.width) * h.height * h.channels, 0.f);
  for (std::uint32_t y = 0; y < h.height; ++y)
    for (std::uint32_t x = 0; x < h.width; ++x) {
      const std::uint32_t x1 = std::min(image.width, 2 * x + 2), y1 = std::min(image.height, 2 * y + 2);
      const float n = float((x1 - 2 * x) * (y1 - 2 * y));
      for (std::uint32_t c = 0; c < image.channels; ++c) {
        float s = 0;
        for (std::uint32_t yy = 2 * y; yy < y1; ++yy)
          for (std::uint32_t xx = 2 * x; xx < x1; ++xx) s += image.at(xx, yy, c);
        h.pixels[(std::size_t(y) * h.width + x) * h.channels + c] = s / n;
      }
    }
  return h;
}

std::vector<std::uint8_t> halve_mask(const std::vector<std::uint8_t>& mask, std::uint32_t width, std::uint32_t height) {
  const std::uint32_t W = (width + 1) / 2, H = (height + 1) / 2;
  std::vector<std::uint8_t> h(std::size_t(W) * H, 0);
  for (std::uint32_t y = 0; y < height; ++y)
    for (std::uint32_t x = 0; x < width; ++x)
      if (mask[std::size_t(y) * width + x]) h[std::size_t(y / 2) * W + x / 2] = 1;
  return h;
}

std::vector<std::uint8_t> eroded_mask(const std::vector<std::uint8_t>& mask, std::uint32_t width, std::uint32_t height,
                                      std::uint32_t radius) {
  // A summed-area table of the unset pixels: any box's count in O(1).
  const std::size_t TW = std::size_t(width) + 1;
  std::vector<std::uint32_t> outside(TW * (height + 1), 0);
  for (std::uint32_t y = 0; y < height; ++y)
    for (std::uint32_t x = 0; x < width; ++x) {
      const std::size_t at = (y + 1) * TW + x + 1;
      outside[at] = (mask[std::size_t(y) * width + x] ? 0u : 1u) + outside[at - 1] + outside[at - TW] - outside[at - TW - 1];
    }
  std::vector<std::uint8_t> inner(mask.size(), 0);
  for (std::uint32_t y = radius; y + radius < height; ++y)
    for (std::uint32_t x = radius; x + radius < width; ++x) {
      const std::size_t top = (y - radius) * TW, bottom = (y + radius + 1) * TW;
      const std::uint32_t count =
          outside[bottom + x + radius + 1] - outside[top + x + radius + 1] - outside[bottom + x - radius] + outside[top + x - radius];
      inner[std::size_t(y) * width + x] = count == 0 ? 1 : 0;
    }
  return inner;
}

ScaledOrientation scaled_orientation(const io::Image& image, const std::vector<std::uint8_t>& mask, std::uint32_t scales,
                                     std::uint32_t window, const OrientationOf& orientation_of, std::uint32_t outline,
                                     const OrientationMap* finest) {
  if (scales < 1) throw InputError("orientation scales: at least one scale is needed (got 0)");
  if (mask.size() != std::size_t(image.width) * image.height)
    throw InputError("orientation scales: the mask has " + std::to_string(mask.size()) + " pixels, the image " +
                     std::to_string(std::size_t(image.width) * image.height));
  ScaledOrientation out;
  out.width = image.width, out.height = image.height;
  const std::size_t n = std::size_t(image.width) * image.height;
  out.angle.assign(n, 0.f), out.reliability.assign(n, -1.f), out.scale.assign(n, 0);
  io::Image level = image;
  std::vector<std::uint8_t> level_mask = mask;
  for (std::uint32_t s = 0; s < scales; ++s) {
    if (s > 0) {
      if ((std::min(level.width, level.height) + 1) / 2 < 16) break;  // the halved side would fall below 16 px
      level_mask = halve_mask(level_mask, level.width, level.height);
      level = halve(level);
    }
    const OrientationMap map = s == 0 && finest ? *finest : orientation_of(level, level_mask);
    const std::vector<float> reliability = orientation_reliability(map, window);
    const std::vector<std::uint8_t> away = s > 0 && outline > 0 ? eroded_mask(level_mask, level.width, level.height, outline)
                                                                 : std::vector<std::uint8_t>{};
    for (std::uint32_t y = 0; y < image.height; ++y)
      for (std::uint32_t x = 0; x < image.width; ++x) {
        const std::size_t i = std::size_t(y) * image.width + x, at = std::size_t(y >> s) * level.width + (x >> s);
        if (!away.empty() && !away[at]) continue;
        if (reliability[at] > out.reliability[i])
          out.reliability[i] = reliability[at], out.angle[i] = map.orientation.pixels[at], out.scale[i] = std::uint8_t(s);
      }
  }
  for (float& r : out.reliability) r = std::max(r, 0.f);
  return out;
}

}  // namespace nf::orient
