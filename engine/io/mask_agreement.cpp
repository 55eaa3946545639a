#include "engine/io/mask_agreement.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>

namespace nf::io {

double mask_edge_contrast(const std::vector<std::uint8_t>& rgb, const std::vector<std::uint8_t>& mask, std::uint32_t width,
                          std::uint32_t height, int dx, int dy) {
  const auto masked = [&](std::uint32_t x, std::uint32_t y) {
    const long sx = long(x) - dx, sy = long(y) - dy;
    return sx >= 0 && sy >= 0 && sx < long(width) && sy < long(height) && mask[std::size_t(sy) * width + std::size_t(sx)] != 0;
  };
  double all = 0, edge = 0;
  std::uint64_t all_count = 0, edge_count = 0;
  const auto step = [&](std::size_t a, std::size_t b, bool edge_between) {
    int d = 0;
    for (int k = 0; k < 3; ++k) d += std::abs(int(rgb[3 * a + k]) - int(rgb[3 * b + k]));
    all += d, ++all_count;
    if (edge_between) edge += d, ++edge_count;
  };
  for (std::uint32_t y = 0; y < height; ++y)
    for (std::uint32_t x = 0; x < width; ++x) {
      const std::size_t p = std::size_t(y) * width + x;
      const bool here = masked(x, y);
      if (x + 1 < width) step(p, p + 1, here != masked(x + 1, y));
      if (y + 1 < height) step(p, p + width, here != masked(x, y + 1));
    }
  if (edge_count == 0 || all <= 0) return std::numeric_limits<double>::quiet_NaN();
  return (edge / double(edge_count)) / (all / double(all_count));
}

double mask_edge_peak(const std::vector<std::uint8_t>& rgb, const std::vector<std::uint8_t>& mask, std::uint32_t width,
                      std::uint32_t height) {
  const int k = std::max(2, int(std::lround(0.04 * std::max(width, height))));
  const double own = mask_edge_contrast(rgb, mask, width, height);
  double moved = 0;
  int count = 0;
  for (const auto& [dx, dy] : {std::pair{k, 0}, {-k, 0}, {0, k}, {0, -k}}) {
    const double c = mask_edge_contrast(rgb, mask, width, height, dx, dy);
    if (std::isfinite(c)) moved += c, ++count;
  }
  if (!std::isfinite(own) || count == 0 || !(moved > 0)) return std::numeric_limits<double>::quiet_NaN();
  return own / (moved / count);
}

}  // namespace nf::io
