#include "engine/synth/photo_effects.hpp"

#include <algorithm>

namespace nf::synth {

io::Image motion_blur(const io::Image& image, std::uint32_t length) {
  const int half = int(length / 2);
  io::Image out = image;
  const float weight = 1.0f / float(2 * half + 1);
  for (std::uint32_t y = 0; y < image.height; ++y)
    for (std::uint32_t x = 0; x < image.width; ++x)
      for (std::uint32_t c = 0; c < image.channels; ++c) {
        float sum = 0;
        for (int d = -half; d <= half; ++d) sum += image.at(std::uint32_t(std::clamp(int(x) + d, 0, int(image.width) - 1)), y, c);
        out.pixels[(std::size_t(y) * image.width + x) * image.channels + c] = sum * weight;
      }
  return out;
}

}  // namespace nf::synth
