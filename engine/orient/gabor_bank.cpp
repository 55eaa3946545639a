#include "engine/orient/gabor_bank.hpp"

#include <algorithm>
#include <string>

#include "engine/core/error.hpp"

namespace nf::orient {
namespace {

// Bounds that keep the GPU kernel's per-invocation arrays (responses, pair sums) reasonable.
constexpr std::uint32_t kMaxOrientations = 720;
constexpr int kMaxRadius = 24;
constexpr float kMaxDogSigma = 100.f;

void require_positive(float value, const char* field) {
  if (!(value > 0) || !std::isfinite(value))
    throw InputError(std::string("Gabor parameter ") + field + " must be a positive finite number, got " +
                     std::to_string(value));
}

void require_dog_sigma(float value, const char* field) {
  if (!(value >= 0 && value <= kMaxDogSigma))
    throw InputError(std::string("Gabor parameter ") + field + " must be in [0, " + std::to_string(kMaxDogSigma) +
                     "] px, got " + std::to_string(value));
}

int gabor_radius(const GaborParams& p) { return int(std::floor(p.support * std::max(p.sigma_x, p.sigma_y))); }

}  // namespace

void validate(const GaborParams& p) {
  require_positive(p.sigma_x, "sigma_x");
  require_positive(p.sigma_y, "sigma_y");
  require_positive(p.frequency, "frequency");
  require_positive(p.support, "support");
  require_dog_sigma(p.dog_low_sigma, "dog_low_sigma");
  require_dog_sigma(p.dog_high_sigma, "dog_high_sigma");
  if (p.orientations < 2 || p.orientations > kMaxOrientations)
    throw InputError("Gabor parameter orientations must be in [2, " + std::to_string(kMaxOrientations) + "], got " +
                     std::to_string(p.orientations));
  const std::uint32_t ppi = p.pixels_per_invocation;
  if (ppi > 8 || (ppi & (ppi - 1)) != 0)
    throw InputError("Gabor parameter pixels_per_invocation must be 0 (automatic) or 1, 2, 4 or 8, got " +
                     std::to_string(ppi));
  if (gabor_radius(p) > kMaxRadius)
    throw InputError("Gabor kernel radius support * max(sigma_x, sigma_y) = " + std::to_string(gabor_radius(p)) +
                     " px exceeds " + std::to_string(kMaxRadius) + " px");
}

GaborBank make_gabor_bank(const GaborParams& p) {
  validate(p);
  GaborBank bank;
  bank.orientations = p.orientations;
  const double reach = double(p.support) * std::max(p.sigma_x, p.sigma_y);
  const int r = gabor_radius(p);
  bank.taps.push_back({0, 0});
  for (int dy = 0; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx)
      if ((dy > 0 || dx > 0) && dx * dx + dy * dy <= reach * reach) {
        bank.taps.push_back({dx, dy});
        bank.radius = std::max({bank.radius, std::abs(dx), dy});
      }
  const double sx2 = double(p.sigma_x) * p.sigma_x, sy2 = double(p.sigma_y) * p.sigma_y;
  const double norm = 1.0 / (2 * kPi * p.sigma_x * p.sigma_y);
  bank.weights.resize(std::size_t(p.orientations) * bank.taps.size());
  for (std::uint32_t o = 0; o < p.orientations; ++o) {
    const double theta = bank.theta(o), s = std::sin(theta), c = std::cos(theta);
    for (std::size_t k = 0; k < bank.taps.size(); ++k) {
      const double x = bank.taps[k].dx, y = bank.taps[k].dy;
      const double a = x * s + y * c;   // across the strand: p . n
      const double b = x * c - y * s;   // along the strand:  p . t
      bank.weights[o * bank.taps.size() + k] =
          norm * std::exp(-0.5 * (a * a / sx2 + b * b / sy2)) * std::cos(2 * kPi * p.frequency * a);
    }
  }
  for (std::uint32_t o = 0; o < p.orientations; ++o) {
    const double d = orientation_distance(bank.theta(o), 0.0);
    bank.distance2_sum += d * d;
  }
  return bank;
}

std::vector<double> gaussian_half_taps(float sigma) {
  if (sigma <= 0) return {1.0};
  const int r = int(4.0 * sigma + 0.5);
  std::vector<double> taps(std::size_t(r) + 1);
  double sum = 0;
  for (int k = 0; k <= r; ++k) {
    taps[std::size_t(k)] = std::exp(-0.5 * k * k / (double(sigma) * sigma));
    sum += k == 0 ? taps[0] : 2 * taps[std::size_t(k)];
  }
  for (double& t : taps) t /= sum;
  return taps;
}

}  // namespace nf::orient
