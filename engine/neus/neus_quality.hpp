#pragma once
// The surface stage's quality presets (`--quality draft|default|paper`): network, training and
// mesh settings that trade time for accuracy. `paper` is the paper's NeuS (frequency-encoded
// 8 x 256 SDF, 4 x 256 colour network; no skip connection here) and its 300k iterations.
#include <string>

#include "engine/neus/neus_field.hpp"
#include "engine/neus/neus_trainer.hpp"
#include "engine/neus/visual_hull.hpp"

namespace nf::neus {

struct NeusQuality {
  std::string name;
  NeusFieldConfig field;
  NeusTrainingOptions training;
  VisualHullOptions hull;
  int hold_out_every = 8;       // every 8th view is held out for PSNR
  int mesh_resolution = 256;    // marching-cubes cells along the box's longest axis
  std::string mesh;             // an envelope of the user's own used instead of training (empty: train)
};

// InputError naming the preset when it is unknown.
NeusQuality quality_preset(const std::string& name);

}  // namespace nf::neus
