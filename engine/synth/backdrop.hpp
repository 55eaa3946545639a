#pragma once
// What the synthetic photos show around the animal. Plain: one flat colour (a studio backdrop,
// which a mask can threshold). Textured: a floor under the paws and a distant round wall, both with
// a procedural multi-scale pattern fixed in the world, as real photos have around an animal: the
// features structure-from-motion matches off the animal, and a background no threshold separates.
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace nf::synth {

struct Backdrop {
  bool textured = false;
  glm::vec3 plain{0.05f, 0.05f, 0.06f};  // linear RGB, the plain backdrop
  // The textured room in the render frame (y up): the floor's height, the wall's axis (through
  // `centre`, along y) and radius, and the size of the pattern's coarsest blotches.
  glm::vec3 centre{0.f};
  float floor_y = 0, wall_radius = 1, feature_size = 0.05f;
};

const std::vector<std::string>& backdrop_names();  // plain, textured
bool backdrop_is_textured(const std::string& name);  // UsageError for an unknown name

// The linear RGB a ray from `origin` (inside the room) along unit `dir` sees when it misses the animal.
glm::vec3 backdrop_color(const Backdrop& backdrop, glm::vec3 origin, glm::vec3 dir);

}  // namespace nf::synth
