#include "engine/prepare/keypoint_cover.hpp"

#include <algorithm>
#include <cmath>

namespace nf::prepare {

std::string KeypointCover::reason() const {
  return "its automatic mask holds " + std::to_string(inside) + " of the " + std::to_string(seen) + " keypoints its photo has on the animal and " +
         std::to_string(background_inside) + " on the background (a patch of background that size holds " + std::to_string(std::lround(background_expected)) +
         "): the pose puts the animal where the photo does not show it";
}

std::vector<KeypointCover> animal_keypoint_cover(const std::vector<io::Camera>& cameras, const SparsePoints& points, const std::vector<char>& animal,
                                                 const std::vector<char>& background,
                                                 const std::vector<std::vector<std::uint8_t>>& masks) {
  std::vector<KeypointCover> covers(cameras.size());
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const io::Camera& c = cameras[i];
    const auto observed = points.observed.find(c.image.filename().string());
    if (observed == points.observed.end() || masks[i].size() != std::size_t(c.width) * c.height) continue;
    const int w = int(c.width), h = int(c.height), grace = std::max(2, int(std::lround(0.01 * std::max(w, h))));
    // Within `grace` of the mask (held) and with all of that disc in the mask (deep).
    const auto count_disc = [&](int x, int y) {
      std::size_t in = 0, all = 0;
      for (int dy = -grace; dy <= grace; ++dy)
        for (int dx = -grace; dx <= grace; ++dx) {
          const int u = x + dx, v = y + dy;
          if (dx * dx + dy * dy > grace * grace) continue;
          ++all;
          in += u >= 0 && v >= 0 && u < w && v < h && masks[i][std::size_t(v) * c.width + std::size_t(u)] != 0;
        }
      return std::pair{in, all};
    };
    std::size_t background_seen = 0;
    for (const Observation& ob : observed->second) {
      const int x = int(std::floor(ob.pixel.x)), y = int(std::floor(ob.pixel.y));
      if (x < 0 || y < 0 || x >= w || y >= h) continue;
      if (animal[ob.point]) {
        ++covers[i].seen;
        covers[i].inside += count_disc(x, y).first > 0;
      } else if (background[ob.point]) {
        ++background_seen;
        const auto [in, all] = count_disc(x, y);
        covers[i].background_inside += in == all;
      }
    }
    // The background keypoints' density where the photo shows background, times the mask's area.
    const std::size_t area = std::size_t(std::count_if(masks[i].begin(), masks[i].end(), [](std::uint8_t m) { return m != 0; }));
    const std::size_t rest = masks[i].size() - area;
    if (rest > 0) covers[i].background_expected = double(background_seen) * double(area) / double(rest);
  }
  return covers;
}

}  // namespace nf::prepare
