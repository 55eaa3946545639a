#pragma once
// Lengths from the photos (issue: fur stage, lengths learned from the images): each region's fur
// length is the knowledge's length x the metric scale x a factor the fur stage optimises with the
// field. The factor is bounded: lambda = exp(log lo + (log hi - log lo) sigmoid(u)) over an
// unconstrained u, so no step can take it outside [lo, hi] or to a non-positive length, and u = 0
// gives 1 when the bounds are reciprocal (0.4 and 2.5).
//
// Its gradient comes from the strand geometry map's adjoint (strand_geometry_ref.hpp), which
// already gives dLoss/dl for each strand's length l: with l_k = lambda_r l0_k for a strand of
// region r and knowledge length l0_k, dLoss/dlambda_r = sum over the batch's strands of region r of
// dLoss/dl_k l0_k.
#include <cmath>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/fur/roots.hpp"
#include "engine/fur/strand_geometry_ref.hpp"

namespace nf::fur {

struct LengthFactorBounds {
  double lo = 0.4, hi = 2.5;
  void validate() const;  // InputError naming the field
};

// lambda(u), u(lambda) (lambda clamped into the bounds) and dlambda/du, in T (float or double).
template <class T>
T length_factor_of(T raw, const LengthFactorBounds& b) {
  if (b.hi <= b.lo) return T(b.lo);
  const T a = T(std::log(b.lo)), c = T(std::log(b.hi));
  return std::exp(a + (c - a) / (T(1) + std::exp(-raw)));
}
double length_factor_raw(double factor, const LengthFactorBounds& b);
template <class T>
T length_factor_derivative(T raw, const LengthFactorBounds& b) {
  if (b.hi <= b.lo) return T(0);
  const T s = T(1) / (T(1) + std::exp(-raw));
  return length_factor_of(raw, b) * T(std::log(b.hi) - std::log(b.lo)) * s * (T(1) - s);
}

// dLoss/dlambda per region (`regions` entries) of a batch: each strand's region and knowledge
// length, and the strand geometry adjoint's frame gradients (kFrameFloats per strand, the length
// at 3). Accumulated in double.
template <class T>
std::vector<double> length_factor_gradients(std::span<const std::int32_t> region, std::span<const T> base_length,
                                            std::span<const T> grad_frames, std::size_t regions) {
  std::vector<double> g(regions, 0.0);
  for (std::size_t k = 0; k < region.size() && k < base_length.size() && (k + 1) * kFrameFloats <= grad_frames.size(); ++k)
    if (region[k] >= 0 && std::size_t(region[k]) < regions)
      g[std::size_t(region[k])] += double(grad_frames[k * kFrameFloats + 3]) * double(base_length[k]);
  return g;
}

// One entry per region that has roots: its factor, the roots' share, and the metric scale that the
// factor implies (the knowledge's scale divided by it: strands lambda times longer mean a scene
// unit is lambda times fewer cm).
json length_factors_json(const std::vector<float>& factors, const Roots& roots, double cm_per_unit,
                         const std::function<std::string(std::int32_t)>& region_name);

}  // namespace nf::fur
