#include "engine/fur/length_factors.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/error.hpp"

namespace nf::fur {

void LengthFactorBounds::validate() const {
  if (!(lo > 0) || !std::isfinite(lo) || !(hi >= 1) || !std::isfinite(hi) || !(lo <= 1))
    throw InputError("fur training options: the length factor's bounds must be finite with 0 < length_min <= 1 <= length_max (given " +
                     std::to_string(lo) + " and " + std::to_string(hi) + ")");
}

double length_factor_raw(double factor, const LengthFactorBounds& b) {
  if (b.hi <= b.lo) return 0;
  const double a = std::log(b.lo), c = std::log(b.hi);
  // A share strictly inside (0, 1): a factor at a bound maps to a large but finite u.
  const double share = std::clamp((std::log(std::clamp(factor, b.lo, b.hi)) - a) / (c - a), 1e-6, 1 - 1e-6);
  return std::log(share / (1 - share));
}

json length_factors_json(const std::vector<float>& factors, const Roots& roots, double cm_per_unit,
                         const std::function<std::string(std::int32_t)>& region_name) {
  std::vector<std::size_t> count(factors.size(), 0);
  for (std::int32_t r : roots.region)
    if (r >= 0 && std::size_t(r) < count.size()) ++count[std::size_t(r)];
  json regions = json::object();
  double log_sum = 0;
  std::size_t counted = 0;
  for (std::size_t r = 0; r < factors.size(); ++r) {
    if (!count[r]) continue;
    regions[region_name(std::int32_t(r))] = {{"factor", factors[r]}, {"roots_share", double(count[r]) / double(std::max<std::size_t>(1, roots.size()))}};
    log_sum += double(count[r]) * std::log(double(factors[r])), counted += count[r];
  }
  const double mean = counted ? std::exp(log_sum / double(counted)) : 1.0;
  // Strands lambda times longer in scene units than the knowledge x scale: a scene unit is lambda
  // times fewer cm, if the knowledge's lengths in cm are right.
  return {{"regions", regions}, {"factor_geometric_mean", mean}, {"cm_per_unit_implied", cm_per_unit / mean}, {"cm_per_unit_used", cm_per_unit}};
}

}  // namespace nf::fur
