#include "engine/synth/camera_rig.hpp"

#include <cmath>
#include <cstdio>
#include <random>

#include "engine/core/error.hpp"

namespace nf::synth {

std::vector<io::Camera> camera_rings(glm::vec3 centre, float radius, glm::vec3 up, const RigOptions& o) {
  if (o.views == 0 || o.width == 0 || o.height == 0) throw UsageError("synthetic cameras: views and resolution must be positive");
  constexpr double kPi = 3.14159265358979;
  const double half_fov = 0.5 * o.fov_deg * kPi / 180.0;
  const double fy = 0.5 * o.height / std::tan(half_fov);
  // The narrower of the two axes decides the distance.
  const double half_fov_min = std::atan(0.5 * std::min(o.width, o.height) / fy);
  const double distance = radius * o.margin / std::sin(half_fov_min);
  const glm::dvec3 u = glm::normalize(glm::dvec3(up));
  const glm::dvec3 a = glm::normalize(glm::cross(u, std::fabs(u.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 0, 1)));
  const glm::dvec3 b = glm::cross(a, u);
  const std::uint32_t low = (o.views + 1) / 2, high = o.views - low;
  std::vector<io::Camera> cameras;
  std::mt19937_64 rng(0x9e3779b97f4a7c15ull ^ o.seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto jitter = [&](double amount) { return o.handheld ? amount * unit(rng) : 0.0; };
  for (std::uint32_t i = 0; i < o.views; ++i) {
    const bool on_low = i < low;
    const std::uint32_t k = on_low ? i : i - low, count = on_low ? low : high;
    const double azimuth = 2 * kPi * (k + (on_low ? 0.0 : 0.5) + jitter(1.0 / 3.0)) / count;
    const double elevation = ((on_low ? o.low_elevation_deg : o.high_elevation_deg) + jitter(4.0)) * kPi / 180.0;
    const glm::dvec3 dir = std::cos(elevation) * (std::cos(azimuth) * a + std::sin(azimuth) * b) + std::sin(elevation) * u;
    const double walk = o.handheld ? 1.05 + jitter(0.10) : 1.0;
    const glm::dvec3 aim = glm::dvec3(centre) + glm::dvec3(jitter(0.05), jitter(0.05), jitter(0.05)) * double(radius);
    const glm::dvec3 eye = glm::dvec3(centre) + walk * distance * dir;
    const glm::dvec3 back = glm::normalize(eye - aim);  // the camera looks down -z, towards the aim
    const double roll = jitter(5.0) * kPi / 180.0;
    const glm::dvec3 level = glm::normalize(glm::cross(u, back));
    const glm::dvec3 right = std::cos(roll) * level + std::sin(roll) * glm::cross(back, level);
    const glm::dvec3 cam_up = glm::cross(back, right);
    io::Camera c;
    char name[16];
    std::snprintf(name, sizeof name, "%03u", i);
    c.name = name;
    c.width = o.width, c.height = o.height;
    c.fx = c.fy = fy;
    c.cx = 0.5 * o.width, c.cy = 0.5 * o.height;
    c.camera_to_world = glm::dmat4(glm::dvec4(right, 0), glm::dvec4(cam_up, 0), glm::dvec4(back, 0), glm::dvec4(eye, 1));
    cameras.push_back(c);
  }
  return cameras;
}

}  // namespace nf::synth
