#include "engine/orient/angle_error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "engine/core/error.hpp"
#include "engine/orient/gabor_bank.hpp"

namespace nf::orient {

float median_angle_difference_deg(const io::Image& orientation, const io::Image& confidence,
                                  const io::Image& reference_orientation, const std::vector<std::uint8_t>& valid) {
  const std::size_t n = std::size_t(orientation.width) * orientation.height;
  for (const io::Image* image : {&orientation, &confidence, &reference_orientation})
    if (image->width != orientation.width || image->height != orientation.height || image->channels != 1 ||
        image->pixels.size() != n)
      throw InputError("median angle difference: the orientation, confidence and reference images must be "
                       "1-channel images of the same size");
  if (valid.size() != n)
    throw InputError("median angle difference: " + std::to_string(valid.size()) + " valid flags for " +
                     std::to_string(n) + " pixels");
  std::vector<double> diffs;
  for (std::size_t i = 0; i < n; ++i) {
    const float ref = reference_orientation.pixels[i];
    if (!valid[i] || !(confidence.pixels[i] > 0) || !std::isfinite(ref) || !std::isfinite(orientation.pixels[i]))
      continue;
    diffs.push_back(orientation_distance(orientation.pixels[i], ref) * 180.0 / kPi);
  }
  if (diffs.empty()) return std::numeric_limits<float>::quiet_NaN();
  const std::size_t mid = diffs.size() / 2;
  std::nth_element(diffs.begin(), diffs.begin() + std::ptrdiff_t(mid), diffs.end());
  double median = diffs[mid];
  if (diffs.size() % 2 == 0) median = 0.5 * (median + *std::max_element(diffs.begin(), diffs.begin() + std::ptrdiff_t(mid)));
  return float(median);
}

}  // namespace nf::orient
