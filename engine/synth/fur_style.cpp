#include "engine/synth/fur_style.hpp"

#include <cmath>

namespace nf::synth {

using body::Region;

FurStyle fur_style(const std::string& animal) {
  FurStyle s;
  if (animal == "dog") s.lift_deg = 22, s.clump_strength = 0.3f, s.wave_amplitude = 0.01f;
  if (animal == "fox") s.lift_deg = 35, s.clump_strength = 0.55f, s.wave_amplitude = 0.03f, s.gravity = 0.25f;
  if (animal == "panda") s.lift_deg = 40, s.clump_strength = 0.6f, s.wave_amplitude = 0.05f, s.curl_radius = 0.03f, s.curl_turns = 1.0f, s.gravity = 0.3f;
  if (animal == "tiger") s.lift_deg = 28, s.clump_strength = 0.4f;
  if (animal == "lion") s.lift_deg = 26, s.mane_wave_amplitude = 0.08f, s.gravity = 0.35f;
  return s;
}

namespace {

glm::vec3 rgb(int r, int g, int b) {  // sRGB bytes -> linear
  auto lin = [](int c) { return std::pow(float(c) / 255.0f, 2.2f); };
  return {lin(r), lin(g), lin(b)};
}

float smooth_step(float e0, float e1, float x) {
  const float t = std::fmin(std::fmax((x - e0) / (e1 - e0), 0.0f), 1.0f);
  return t * t * (3 - 2 * t);
}

bool under_side(Region r) { return r == Region::belly || r == Region::under_tail; }

}  // namespace

glm::vec3 coat_color(const std::string& animal, Region region, glm::vec3 p, glm::vec3 n, float torso) {
  const glm::vec3 white = rgb(236, 232, 222), black = rgb(28, 26, 26);
  const bool chin = region == Region::face && n.y < -0.3f;
  const bool paw = region == Region::paws || region == Region::front_paws;
  const bool leg = region == Region::leg_front || region == Region::leg_rear;
  if (animal == "panda") {
    // Black legs, ears, shoulder band and eye patches (front-facing face, off the midline).
    const bool band = region == Region::body && std::fabs(p.z - 0.42f * torso) < 0.16f * torso;
    const bool eye_patch = region == Region::face && n.z > 0.3f && std::fabs(n.x) > 0.25f && n.y > -0.1f;
    return leg || paw || region == Region::ears || band || eye_patch ? black : white;
  }
  if (animal == "tiger" || animal == "lion") {
    const glm::vec3 base = animal == "lion" ? rgb(196, 150, 92) : rgb(214, 120, 40);
    if (animal == "lion" && region == Region::mane) return rgb(120, 72, 38);
    if (under_side(region) || chin) return animal == "lion" ? rgb(222, 196, 150) : white;
    if (animal == "lion") return base;
    // Tiger: vertical stripes that wobble with height.
    const float phase = p.z / (0.09f * torso) + 0.8f * std::sin(p.y / (0.07f * torso) + p.x * 3.0f / torso);
    const float stripe = smooth_step(0.72f, 0.86f, 0.5f + 0.5f * std::sin(6.2831853f * phase));
    return base * (1 - stripe) + black * stripe;
  }
  if (animal == "fox") {
    if (under_side(region) || chin || (region == Region::neck && n.y < -0.2f)) return white;
    if (paw) return black;
    if (region == Region::tail && p.z < -1.25f * torso) return white;  // the white tail tip
    return rgb(200, 96, 32);
  }
  if (animal == "dog") {  // beagle tricolour
    if (under_side(region) || leg || paw || chin || region == Region::neck || (region == Region::tail && p.y > 1.3f * torso))
      return white;
    if (region == Region::body && n.y > 0.5f && std::fabs(p.z) < 0.45f * torso) return black;  // the saddle
    return rgb(176, 104, 48);
  }
  // cat: orange tabby, bands along the body.
  if (under_side(region) || chin) return rgb(230, 200, 160);
  const float band = smooth_step(0.55f, 0.9f, 0.5f + 0.5f * std::sin(p.z / (0.045f * torso) + 1.5f * std::sin(p.y / (0.05f * torso))));
  return rgb(212, 128, 56) * (1 - 0.45f * band);
}

glm::vec3 skin_color(const std::string& animal, Region region) {
  switch (region) {
    case Region::eyes: return animal == "panda" ? rgb(20, 16, 14) : rgb(120, 110, 30);
    case Region::nosetip: return animal == "cat" ? rgb(200, 120, 120) : rgb(30, 26, 26);
    case Region::paw_pads: return rgb(40, 34, 34);
    case Region::inner_earcanal: return rgb(200, 150, 140);
    default: return rgb(150, 120, 110);
  }
}

}  // namespace nf::synth
