#pragma once
// Ground-truth fur for synthetic scenes: strands grown on a body mesh from per-region knowledge
// (length in cm, growth direction in the animal frame; bald regions grow nothing) with the
// variation of real coats: length jitter, direction noise, smooth bending, wave, curl, clumping
// and sag, kept outside the body.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/io/mesh.hpp"
#include "engine/io/strands.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/synth/fur_style.hpp"

namespace nf::synth {

struct GrowOptions {
  std::uint32_t strand_count = 100000;
  std::uint32_t points_per_strand = 100;
  unsigned seed = 1;
  float cm_per_unit = 100.0f;
  glm::mat4 animal_to_world{1.0f};  // rigid map of the animal frame into the mesh's frame
  std::string animal;               // for coat colours
  float torso_length = 1.0f;        // pattern scale, scene units
};

struct Fur {
  io::StrandSet strands;             // N x points_per_strand, root first, regions per strand
  std::vector<glm::vec3> root_colors;  // linear RGB per strand
  std::vector<glm::vec3> root_normals;
};

// `body` carries normals and per-vertex regions (world / scene units). Roots are spread with a
// density inversely proportional to the region's length, so short fur is denser and the coat
// covers evenly. Throws InputError when no region of the body grows fur.
Fur grow_fur(const geometry::Mesh& body, const knowledge::Knowledge& knowledge, const FurStyle& style, const GrowOptions& options);

}  // namespace nf::synth
