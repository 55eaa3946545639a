#pragma once
// How a synthetic coat looks beyond the knowledge file: how steeply strands leave the skin, how
// much they wave, curl and clump, their colours and the width they are rendered with. One style
// per animal of `nf_gpu synth`, chosen to resemble the real animal.
#include <string>

#include <glm/glm.hpp>

#include "engine/body/regions.hpp"

namespace nf::synth {

struct FurStyle {
  float lift_deg = 32;             // first segment's angle above the skin
  float lift_tip_fraction = 0.25f; // the tip's angle as a fraction of the root's: fur lies down
  float lift_jitter_deg = 8;
  float direction_noise_deg = 14;  // per-strand turn of the growth direction about the normal
  float bend_noise = 0.08f;        // smooth random bending along the strand (fraction of length)
  float wave_amplitude = 0.02f;    // fraction of length
  float wave_periods = 1.2f;
  float curl_radius = 0.0f;        // fraction of length; > 0 gives helical curls
  float curl_turns = 0.0f;
  float clump_strength = 0.45f;    // 0: none, 1: tips meet their clump's centre strand
  float strands_per_clump = 24;
  float length_jitter = 0.12f;     // relative standard deviation of strand length
  float gravity = 0.15f;           // sag of long fur, grows with length
  float mane_wave_amplitude = 0.06f;
  float strand_radius_fraction = 0.0011f;  // render radius as a fraction of the torso length
};

FurStyle fur_style(const std::string& animal);

// Linear RGB of the coat at a root (animal-frame position and normal, region), before per-strand
// jitter. `torso_length` sets the scale of patterns (tiger stripes, panda patches).
glm::vec3 coat_color(const std::string& animal, body::Region region, glm::vec3 animal_position, glm::vec3 animal_normal,
                     float torso_length);
// Linear RGB of bare skin (eyes, nose, pads, inner ears) and of the body under the fur.
glm::vec3 skin_color(const std::string& animal, body::Region region);

}  // namespace nf::synth
