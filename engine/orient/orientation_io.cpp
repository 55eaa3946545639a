#include "engine/orient/orientation_io.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/error.hpp"

namespace nf::orient {
namespace {

void check_same_size(const OrientationMap& map) {
  const io::Image &o = map.orientation, &c = map.confidence;
  if (o.channels != 1 || c.channels != 1 || o.width != c.width || o.height != c.height ||
      o.pixels.size() != std::size_t(o.width) * o.height || c.pixels.size() != o.pixels.size())
    throw InternalError("orientation map: orientation and confidence images differ in size or are not 1-channel");
}

// Hue in [0, 1) to RGB at full saturation and the given value.
void hsv_to_rgb(float hue, float value, float* rgb) {
  const float h6 = hue * 6.f;
  for (int c = 0; c < 3; ++c) {
    const float k = std::fmod(float(5 - 2 * c) + h6, 6.f);  // R: 5, G: 3, B: 1 (the usual HSV formula)
    rgb[c] = value * (1.f - std::clamp(std::min(k, 4.f - k), 0.f, 1.f));
  }
}

}  // namespace

void write_orientation_exr(const std::filesystem::path& path, const OrientationMap& map) {
  check_same_size(map);
  io::Image both{map.orientation.width, map.orientation.height, 2, {}};
  both.pixels.resize(map.orientation.pixels.size() * 2);
  for (std::size_t i = 0; i < map.orientation.pixels.size(); ++i) {
    both.pixels[2 * i] = map.orientation.pixels[i];
    both.pixels[2 * i + 1] = map.confidence.pixels[i];
  }
  io::write_exr(path, both);
}

OrientationMap read_orientation_exr(const std::filesystem::path& path) {
  const io::Image both = io::read_image(path);
  if (both.channels != 2)
    throw InputError(path.string() + ": an orientation map has 2 channels (orientation, confidence), this file " +
                     std::to_string(both.channels));
  OrientationMap map;
  map.orientation = {both.width, both.height, 1, std::vector<float>(both.pixels.size() / 2)};
  map.confidence = map.orientation;
  for (std::size_t i = 0; i < map.orientation.pixels.size(); ++i) {
    map.orientation.pixels[i] = both.pixels[2 * i];
    map.confidence.pixels[i] = both.pixels[2 * i + 1];
  }
  return map;
}

io::Image orientation_visualisation(const OrientationMap& map) {
  check_same_size(map);
  std::vector<float> nonzero;
  for (const float c : map.confidence.pixels)
    if (c > 0) nonzero.push_back(c);
  float scale = 0;
  if (!nonzero.empty()) {
    const auto q = nonzero.begin() + std::ptrdiff_t((nonzero.size() - 1) * 99 / 100);
    std::nth_element(nonzero.begin(), q, nonzero.end());
    scale = *q;
  }
  io::Image vis{map.orientation.width, map.orientation.height, 3, {}};
  vis.pixels.resize(map.orientation.pixels.size() * 3);
  for (std::size_t i = 0; i < map.orientation.pixels.size(); ++i) {
    const float value = scale > 0 ? std::min(1.f, map.confidence.pixels[i] / scale) : 0.f;
    float hue = float(map.orientation.pixels[i] / kPi);  // doubled angle / (2 pi)
    hue -= std::floor(hue);
    hsv_to_rgb(hue, value, &vis.pixels[3 * i]);
  }
  return vis;
}

void write_orientation_png(const std::filesystem::path& path, const OrientationMap& map) {
  io::write_png(path, orientation_visualisation(map));
}

}  // namespace nf::orient
