#include "engine/core/color.hpp"

#include <algorithm>
#include <cmath>

namespace nf::color {

float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

float linear_to_srgb(float linear) {
  const float c = std::clamp(linear, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

glm::vec3 srgb_to_linear(glm::vec3 c) { return {srgb_to_linear(c.r), srgb_to_linear(c.g), srgb_to_linear(c.b)}; }
glm::vec3 linear_to_srgb(glm::vec3 c) { return {linear_to_srgb(c.r), linear_to_srgb(c.g), linear_to_srgb(c.b)}; }

glm::vec3 lab_of_linear(glm::vec3 c) {
  // sRGB primaries to XYZ, relative to the D65 white point.
  const double x = (0.4124564 * c.r + 0.3575761 * c.g + 0.1804375 * c.b) / 0.95047;
  const double y = 0.2126729 * c.r + 0.7151522 * c.g + 0.0721750 * c.b;
  const double z = (0.0193339 * c.r + 0.1191920 * c.g + 0.9503041 * c.b) / 1.08883;
  const auto f = [](double t) { return t > 216.0 / 24389.0 ? std::cbrt(t) : (24389.0 / 27.0 * t + 16.0) / 116.0; };
  const double fx = f(x), fy = f(y), fz = f(z);
  return {float(116.0 * fy - 16.0), float(500.0 * (fx - fy)), float(200.0 * (fy - fz))};
}

float delta_e(glm::vec3 a, glm::vec3 b) { return glm::distance(lab_of_linear(a), lab_of_linear(b)); }

}  // namespace nf::color
