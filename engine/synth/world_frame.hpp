#pragma once
// The world frame a synthetic scene is written in. `nf_gpu synth` builds and renders the animal in
// its own frame (y up, metres); a WorldFrame re-expresses the result before it is written, so the
// same photos can come with coordinates of another convention (a studio's z-up millimetres, far
// from the origin). Every stage must find frame, units and scale from the data: running the
// pipeline on both versions of one scene checks that it does.
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/io/scene.hpp"
#include "engine/io/strands.hpp"

namespace nf::synth {

// x' = scale * rotation * x + offset (a similarity: rotation proper, scale > 0).
struct WorldFrame {
  std::string name = "y-up-m";
  glm::dmat3 rotation{1.0};
  double scale = 1;  // scene units per metre
  glm::dvec3 offset{0.0};

  glm::dvec3 point(const glm::dvec3& p) const { return scale * (rotation * p) + offset; }
  glm::dvec3 direction(const glm::dvec3& d) const { return rotation * d; }
  glm::dmat4 matrix() const;  // the similarity as a 4 x 4 matrix
};

// "y-up-m" or "z-up-mm"; UsageError naming the others for anything else.
WorldFrame world_frame(const std::string& name);
std::vector<std::string> world_frame_names();

// In place (meshes: geometry::transform_mesh with frame.matrix()): strand points and per-point
// thickness; a camera's pose (its rotation turned, its centre moved; intrinsics unchanged, so its
// photo stays right).
void transform_strands(const WorldFrame& frame, io::StrandSet& strands);
void transform_camera(const WorldFrame& frame, io::Camera& camera);

}  // namespace nf::synth
