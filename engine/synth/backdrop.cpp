#include "engine/synth/backdrop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "engine/core/error.hpp"

namespace nf::synth {

namespace {

float lattice(std::int32_t x, std::int32_t y, std::int32_t z, std::uint32_t seed) {
  std::uint32_t h = seed * 0x9E3779B9u ^ std::uint32_t(x) * 0x85EBCA6Bu ^ std::uint32_t(y) * 0xC2B2AE35u ^ std::uint32_t(z) * 0x27D4EB2Fu;
  h ^= h >> 16, h *= 0x7feb352dU, h ^= h >> 15, h *= 0x846ca68bU, h ^= h >> 16;
  return float(h >> 8) * (1.0f / 16777216.0f);
}

// Value noise in [0, 1], smooth between integer lattice points.
float value_noise(glm::vec3 p, std::uint32_t seed) {
  const glm::vec3 f = glm::floor(p), t = p - f;
  const glm::vec3 s = t * t * (3.f - 2.f * t);
  const auto i = glm::ivec3(f);
  float corners[8];
  for (int c = 0; c < 8; ++c) corners[c] = lattice(i.x + (c & 1), i.y + ((c >> 1) & 1), i.z + ((c >> 2) & 1), seed);
  const auto mix = [](float a, float b, float w) { return a + (b - a) * w; };
  const float x00 = mix(corners[0], corners[1], s.x), x10 = mix(corners[2], corners[3], s.x);
  const float x01 = mix(corners[4], corners[5], s.x), x11 = mix(corners[6], corners[7], s.x);
  return mix(mix(x00, x10, s.y), mix(x01, x11, s.y), s.z);
}

// Five octaves, each half the size: detail at every scale a photo resolves.
float fbm(glm::vec3 p, std::uint32_t seed) {
  float sum = 0, amplitude = 0.5f, total = 0;
  for (int octave = 0; octave < 5; ++octave) {
    sum += amplitude * value_noise(p, seed + std::uint32_t(octave));
    total += amplitude;
    p = 2.03f * p + glm::vec3(17.1f, 5.3f, 11.7f);
    amplitude *= 0.5f;
  }
  return sum / total;
}

// A pattern at world point p (in units of the coarsest blotch): two colours mixed by a smooth field,
// shaded by finer grain, with sharp-edged spots (corners and blobs are what feature detectors find).
glm::vec3 pattern(glm::vec3 p, glm::vec3 a, glm::vec3 b, std::uint32_t seed) {
  const float mixing = std::clamp(1.6f * fbm(p, seed) - 0.3f, 0.f, 1.f);
  glm::vec3 c = a + (b - a) * mixing;
  c *= 0.6f + 0.8f * fbm(4.1f * p, seed + 10);
  const float spots = value_noise(2.7f * p, seed + 20);
  if (spots > 0.68f) c = glm::mix(c, glm::vec3(0.9f, 0.88f, 0.8f), 0.7f);
  else if (spots < 0.22f) c *= 0.25f;
  return c;
}

}  // namespace

const std::vector<std::string>& backdrop_names() {
  static const std::vector<std::string> names = {"plain", "textured"};
  return names;
}

bool backdrop_is_textured(const std::string& name) {
  if (name == "plain") return false;
  if (name == "textured") return true;
  throw UsageError("unknown backdrop '" + name + "' (plain, textured)");
}

glm::vec3 backdrop_color(const Backdrop& b, glm::vec3 origin, glm::vec3 dir) {
  if (!b.textured) return b.plain;
  // The wall: where the ray leaves the vertical cylinder around the centre (the origin is inside).
  const glm::vec2 o(origin.x - b.centre.x, origin.z - b.centre.z), d(dir.x, dir.z);
  const float dd = glm::dot(d, d), od = glm::dot(o, d), oo = glm::dot(o, o) - b.wall_radius * b.wall_radius;
  float t = dd > 0 ? (-od + std::sqrt(std::max(0.f, od * od - dd * oo))) / dd : INFINITY;
  bool floor = false;
  if (dir.y < 0 && origin.y > b.floor_y) {
    const float t_floor = (b.floor_y - origin.y) / dir.y;
    if (t_floor < t) t = t_floor, floor = true;
  }
  if (!std::isfinite(t)) return b.plain;  // straight up or down the axis: no wall to see
  // The wall is several times farther than the floor: larger blotches keep them a few pixels wide.
  const glm::vec3 p = (origin + t * dir) / (floor ? b.feature_size : 4.f * b.feature_size);
  return floor ? pattern(p, {0.30f, 0.22f, 0.13f}, {0.16f, 0.24f, 0.10f}, 1)
               : pattern(p, {0.20f, 0.26f, 0.34f}, {0.42f, 0.40f, 0.36f}, 7);
}

}  // namespace nf::synth
