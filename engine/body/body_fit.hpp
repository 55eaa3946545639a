#pragma once
// Fitting the rigged body model to a scanned surface (M_NeuS, later M_bald) in the paper's three
// stages, each its own Adam schedule over the posing variables (posing.hpp, hand-written adjoint):
//   1. global rotation, translation and scale;
//   2. plus shape coefficients and joint rotations (a pose prior and joint limits keep legs from
//      folding through the body; a shape prior keeps proportions plausible);
//   3. plus per-vertex offsets (Laplacian, edge and normal-consistency regularisers).
// Loss: two-way chamfer between `samples` points drawn on the target every step and the posed
// body's vertices (squared distances, nearest neighbours through geometry::PointIndex), plus the
// regularisers with the paper's weights. Everything runs in a normalised frame (the target centred,
// its RMS radius 1), so units and placement of the scene do not matter.
//
// Initialisation does not depend on the scene's world frame: "up" comes from the cameras' up
// vectors when they agree (else every principal axis of the target is tried both ways), the long
// axis from the target's principal axes across up, and head against tail (and which horizontal
// axis is the long one) by fitting every hypothesis briefly and keeping the best.
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/body/body_model.hpp"
#include "engine/core/json.hpp"
#include "engine/geometry/mesh.hpp"

namespace nf::body {

struct BodyFitWeights {
  double chamfer = 1.0;
  double laplacian = 0.01, edge = 0.8, normal = 0.02;  // the paper's (WLDO's) weights, stage 3
  // The priors are weak next to the chamfer (about 1e-3 for a good fit in the normalised frame):
  // they break ties, they do not hold the pose.
  double pose_prior = 1e-4;    // sum of squared joint angles (radians), stage 2 on
  double joint_limit = 10.0;   // squared excess over the joint's limit
  double shape_prior = 1e-4;   // sum of squared shape coefficients
};

struct BodyFitOptions {
  std::uint32_t samples = 20000;        // target points per step
  std::uint32_t hypothesis_steps = 40;  // stage-1 steps per initial hypothesis
  std::uint32_t global_steps = 120, pose_steps = 250, offset_steps = 120;
  double global_lr = 0.02, pose_lr = 0.01, shape_lr = 0.03, offset_lr = 0.002;
  double max_joint_angle = 1.2;  // radians; ear joints may fold to 2.8
  // The torso's length over its girth kept at least this share of the template's (models with
  // `torso_length` and `torso_girth` shapes; 0: unbounded). Fur that makes an animal a round blob
  // let the fit trade the torso's length for girth until the neck took the chest and the body the
  // legs (a panda's torso shrank to 29 % of its length and grew 73 % in girth; labels 54 %); the
  // families' own torsos lie at 0.78-1.16 of the template's aspect.
  double min_torso_aspect = 0.5;
  BodyFitWeights weights;
  unsigned seed = 1;
};

// What the scene says about its frame, if anything.
struct FrameHints {
  std::optional<glm::dvec3> up;  // world "up" (unit), e.g. the cameras' mean up vector
};

struct FitStageReport {
  std::string name;
  std::uint32_t steps = 0;
  double chamfer_start = 0, chamfer_end = 0;  // mean two-way distance, target units (not squared)
  double loss_end = 0;
  double seconds = 0;
};

struct BodyFit {
  std::vector<double> variables;        // posing.hpp layout with offsets (fit frame)
  glm::dmat4 fit_to_world{1.0};         // the normalisation: fit frame -> world
  geometry::Mesh fitted;                // posed body with offsets, world units, regions, normals
  glm::dmat4 animal_to_world{1.0};      // the root frame's similarity (includes the scale)
  std::vector<FitStageReport> stages;
  json hypotheses = json::array();      // every initial placement tried and its chamfer
  double chamfer_mean = 0;              // final mean two-way distance, world units
  double relative_chamfer = 0;          // chamfer_mean / the target's RMS radius
  bool low_confidence = false;          // relative_chamfer above what a quadruped fit reaches
  bool torso_at_bound = false;          // the torso's aspect ended at min_torso_aspect: the surface is rounder than a body
};

// Throws InputError naming `source` when the target has no faces, NaN vertices or no area.
BodyFit fit_body(const BodyModel& model, const geometry::Mesh& target, const FrameHints& hints,
                 const BodyFitOptions& options, const std::string& source);

// Stages 2 and 3 again from `start` against another surface (M_bald after defurring), in the same
// fit frame so the earlier placement carries over.
BodyFit refit_body(const BodyModel& model, const geometry::Mesh& target, const BodyFit& start,
                   const BodyFitOptions& options, const std::string& source);

// The fit's joint positions, world, in the model's joint order.
std::vector<glm::dvec3> fitted_joints(const BodyModel& model, const BodyFit& fit);

// Eye centres (world) of a fit: the mean of the eye region on each side of the animal (its points in
// the model's region detail, else its vertices).
struct FittedEyes {
  glm::dvec3 left, right;
};
FittedEyes fitted_eyes(const BodyModel& model, const BodyFit& fit);

// Whether the fit treats a joint as an ear's (turning freely, tried drooped): "ear" as a word of
// its name in any case (ear_left, l_ear, LEar, EAR_R), not inside another word (leg_rear, beard).
bool ear_joint(const std::string& name);

// The family's mean proportions (the ears' thickness and tip shape are the first animal's, the
// cat's), the template the body stage fits by default.
BodyModel default_template();

}  // namespace nf::body
