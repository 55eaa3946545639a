#pragma once
// The procedural quadruped family: a rigged body model (body_model.hpp) built from a handful of
// proportions. The surface is a smooth union of round cones and ellipsoids hung on a skeleton,
// extracted by marching cubes; skinning weights, shape blend shapes and region labels follow from
// which primitives a vertex is near, so they need no hand painting:
//  - weights: a softmax over primitive distances, summed per driving joint (top 4 kept);
//  - shape: each shape parameter scales bone lengths or girths of one part (torso, neck, head,
//    muzzle, ears, legs, paws, tail); vertices follow their primitives' local coordinates, which
//    makes the blend shapes exact (the deformation is linear in the parameters);
//  - regions: the nearest primitive's part plus rules on normals and keypoints (pads face down,
//    the belly faces down, the inner ear faces forward, under_tail surrounds the tail root).
// Lengths are in metres. The family is also the default template of the body-fit stage.
#include <string>
#include <vector>

#include "engine/body/body_model.hpp"

namespace nf::body {

struct QuadrupedProportions {
  std::string animal;
  float torso_length = 0.26f;                 // pelvis joint to chest joint
  float chest_radius = 0.085f, waist_radius = 0.07f, hip_radius = 0.072f;  // vertical radii
  float torso_width_ratio = 0.8f;             // lateral / vertical radius
  float front_leg_length = 0.22f, rear_leg_length = 0.24f;  // shoulder / hip joint to the ground
  float leg_radius_top = 0.03f, leg_radius_bottom = 0.016f, paw_radius = 0.022f;
  float neck_length = 0.08f, neck_radius = 0.045f, neck_pitch_deg = 40.0f;
  float head_radius = 0.05f, muzzle_length = 0.03f, muzzle_radius = 0.021f;
  float ear_length = 0.05f, ear_width = 0.045f, ear_thickness = 0.004f, ear_tip_ratio = 0.15f;
  float ear_droop_deg = 0.0f;                 // 0 upright, ~150 hanging (beagle)
  float eye_radius = 0.011f;
  float tail_length = 0.28f, tail_radius_base = 0.017f, tail_radius_tip = 0.011f;
  float tail_pitch_deg = -10.0f, tail_curl_deg = 40.0f;  // pitch > 0 raises the tail
  bool mane = false;
};

// The animals `nf_gpu synth` knows: cat, dog, fox, panda, tiger, lion.
const std::vector<std::string>& known_animals();
// Throws UsageError listing the known animals.
QuadrupedProportions animal_proportions(const std::string& animal);
// How far `nf_gpu synth`'s animals stray from their family unless asked for more.
constexpr float kDefaultProportionSpread = 0.06f;
// Every proportion scaled by a seeded factor in [1 - amount, 1 + amount], each drawn on its own up to
// the default amount; beyond it the head's parts keep within 13 % of the head's factor and the neck
// no wider against the head than the family's. The neck's and tail's pitch swing +-20 and +-40
// degrees at the default amount, up to half as much again beyond it (see the definition).
QuadrupedProportions vary_proportions(const QuadrupedProportions& p, unsigned seed, float amount = kDefaultProportionSpread);

struct QuadrupedBuildOptions {
  float voxel = 0.0f;  // marching-cubes voxel in metres; 0: torso_length / 110
  // The thinnest a slab part (the ears) may be, in metres, so marching cubes sees both its sides;
  // 0: 2.5 voxels. A finer build of a template sets the template's, so their surfaces agree.
  float min_thickness = 0.0f;
};

BodyModel build_quadruped(const QuadrupedProportions& p, const QuadrupedBuildOptions& options = {});

// A mild natural pose (head turn, tail sway, leg swing) drawn from the seed; zero when seed is 0.
BodyParams random_pose(const BodyModel& model, unsigned seed);

}  // namespace nf::body
