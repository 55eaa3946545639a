#include "engine/orient/gabor_ref.hpp"

#include <algorithm>
#include <cmath>

namespace nf::orient {
namespace {

// One separable Gaussian, rows then columns, edges clamped.
std::vector<double> blur(const std::vector<float>& image, int w, int h, float sigma) {
  const std::vector<double> taps = gaussian_half_taps(sigma);
  const int r = int(taps.size()) - 1;
  std::vector<double> rows(image.size()), out(image.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double s = 0;
      for (int k = -r; k <= r; ++k) s += taps[std::size_t(std::abs(k))] * image[std::size_t(y) * w + std::clamp(x + k, 0, w - 1)];
      rows[std::size_t(y) * w + x] = s;
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double s = 0;
      for (int k = -r; k <= r; ++k) s += taps[std::size_t(std::abs(k))] * rows[std::size_t(std::clamp(y + k, 0, h - 1)) * w + x];
      out[std::size_t(y) * w + x] = s;
    }
  return out;
}

}  // namespace

std::vector<double> dog_prefilter_ref(const std::vector<float>& grey, std::uint32_t width, std::uint32_t height,
                                      const GaborParams& params) {
  std::vector<double> dog = blur(grey, int(width), int(height), params.dog_low_sigma);
  if (params.dog_high_sigma > 0) {
    const std::vector<double> high = blur(grey, int(width), int(height), params.dog_high_sigma);
    for (std::size_t i = 0; i < dog.size(); ++i) dog[i] -= high[i];
  }
  return dog;
}

OrientationRef gabor_orientation_ref(const std::vector<float>& grey, std::uint32_t width, std::uint32_t height,
                                     const std::vector<std::uint8_t>* mask, const GaborParams& params,
                                     bool keep_responses) {
  const GaborBank bank = make_gabor_bank(params);
  const std::vector<double> dog = dog_prefilter_ref(grey, width, height, params);
  const int w = int(width), h = int(height);
  const std::uint32_t n = bank.orientations;
  auto at = [&](int x, int y) { return dog[std::size_t(std::clamp(y, 0, h - 1)) * w + std::clamp(x, 0, w - 1)]; };

  OrientationRef out;
  out.orientation.assign(dog.size(), 0.f);
  out.confidence.assign(dog.size(), 0.f);
  if (keep_responses) out.responses.assign(dog.size() * n, 0.0);
  std::vector<double> f(n);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t pixel = std::size_t(y) * w + x;
      if (mask && !(*mask)[pixel]) continue;
      std::uint32_t m = 0;
      for (std::uint32_t i = 0; i < n; ++i) {
        double r = bank.weight(i, 0) * at(x, y);
        for (std::size_t k = 1; k < bank.taps.size(); ++k) {
          const GaborTap& t = bank.taps[k];
          r += bank.weight(i, k) * at(x + t.dx, y + t.dy) + bank.weight(i, k) * at(x - t.dx, y - t.dy);
        }
        f[i] = std::fabs(r);
        if (f[i] > f[m]) m = i;
      }
      double spread = 0;
      for (std::uint32_t i = 0; i < n; ++i) {
        const double d = orientation_distance(bank.theta(i), bank.theta(m));
        spread += d * d * (f[i] - f[m]) * (f[i] - f[m]);
      }
      out.orientation[pixel] = float(bank.theta(m));
      out.confidence[pixel] = float(std::sqrt(spread / bank.distance2_sum));
      if (keep_responses) std::copy(f.begin(), f.end(), out.responses.begin() + std::ptrdiff_t(pixel * n));
    }
  return out;
}

}  // namespace nf::orient
