#pragma once
// Cameras for synthetic scenes: two rings at different elevations looking at the animal, far
// enough that its bounding sphere fits in every view with a margin.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "engine/io/scene.hpp"

namespace nf::synth {

struct RigOptions {
  std::uint32_t views = 36;
  std::uint32_t width = 512, height = 512;
  float fov_deg = 40.0f;                      // vertical field of view
  float low_elevation_deg = 8.0f, high_elevation_deg = 38.0f;
  float margin = 1.05f;                       // bounding sphere radius x margin fills the view
  // A person walking round with a camera instead of a rig: each view's azimuth off by up to a third
  // of a step, its elevation by 4 degrees, its distance by -5..+15 %, its aim by 5 % of the radius
  // and its roll by 5 degrees (seeded).
  bool handheld = false;
  unsigned seed = 1;
};

// Cameras (OpenGL axes) around `centre` with world up `up`; the first ceil(views / 2) on the low
// ring, the rest on the high ring, offset by half a step so the views interleave.
std::vector<io::Camera> camera_rings(glm::vec3 centre, float radius, glm::vec3 up, const RigOptions& options);

}  // namespace nf::synth
