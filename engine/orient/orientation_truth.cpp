#include "engine/orient/orientation_truth.hpp"

#include <algorithm>
#include <string>

#include "engine/core/error.hpp"
#include "engine/core/stats.hpp"
#include "engine/orient/gabor_bank.hpp"
#include "engine/orient/orientation_scales.hpp"

namespace nf::orient {

TruthAgreement agreement_with_truth(const OrientationMap& map, const std::vector<float>& reliability, const OrientationMap& truth,
                                    const std::vector<std::uint8_t>& mask, const TruthOptions& o) {
  const std::uint32_t W = map.orientation.width, H = map.orientation.height;
  const std::size_t n = std::size_t(W) * H;
  if (truth.orientation.width != W || truth.orientation.height != H || truth.confidence.pixels.size() != n || reliability.size() != n ||
      mask.size() != n || map.orientation.pixels.size() != n)
    throw InputError("orientation against the truth: the map is " + std::to_string(W) + "x" + std::to_string(H) + ", the true map " +
                     std::to_string(truth.orientation.width) + "x" + std::to_string(truth.orientation.height) +
                     ", and reliability and mask must have a value per pixel");
  const std::vector<std::uint8_t> inside = eroded_mask(mask, W, H, o.outline);
  std::vector<double> all, reliable;
  std::array<std::vector<double>, 5> bins;
  double weighted = 0, weights = 0, reliability_sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!inside[i] || !(truth.confidence.pixels[i] >= o.min_truth_weight)) continue;
    const double error = orientation_distance(map.orientation.pixels[i], truth.orientation.pixels[i]) * 180.0 / kPi;
    all.push_back(error);
    reliability_sum += reliability[i];
    if (reliability[i] >= o.reliable) reliable.push_back(error);
    bins[std::min<std::size_t>(4, std::size_t(std::max(0.f, reliability[i]) * 5))].push_back(error);
    weighted += reliability[i] * error, weights += reliability[i];
  }
  TruthAgreement a;
  if (all.empty()) return a;
  a.pixels = all.size();
  a.median_error_deg = median(all);
  a.reliable_share = double(reliable.size()) / double(all.size());
  a.median_error_reliable_deg = median(reliable);
  a.weighted_error_deg = weights > 0 ? weighted / weights : 0;
  a.mean_reliability = reliability_sum / double(all.size());
  for (std::size_t b = 0; b < bins.size(); ++b) {
    a.share_by_reliability[b] = double(bins[b].size()) / double(all.size());
    a.median_error_by_reliability[b] = median(bins[b]);
  }
  return a;
}

}  // namespace nf::orient
