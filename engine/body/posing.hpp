#pragma once
// The body model posed from one flat vector of variables, in double, with its hand-written adjoint:
// what the body fit optimises. The variables, in order:
//   [0, 3)   global rotation, axis-angle (animal frame -> fit frame)
//   [3, 6)   translation (fit frame)
//   [6]      log of the uniform scale
//   S        shape coefficients
//   3 J      local joint rotations, axis-angle (the root's is held at zero by the fit: the global
//            rotation plays its part)
//   3 V      per-vertex offsets in the rest pose (animal frame), when the layout has them
// Forward (as body_model.cpp's pose_body): rest = template + shape blend + offsets; joints from the
// joint blend; linear blend skinning; world = scale * R * animal + translation.
#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

#include "engine/body/body_model.hpp"

namespace nf::body {

struct PoseLayout {
  std::size_t shapes = 0, joints = 0, vertices = 0;
  bool offsets = false;

  static constexpr std::size_t kGlobal = 7;
  std::size_t shape_begin() const { return kGlobal; }
  std::size_t joint_begin() const { return kGlobal + shapes; }
  std::size_t offset_begin() const { return kGlobal + shapes + 3 * joints; }
  std::size_t size() const { return offset_begin() + (offsets ? 3 * vertices : 0); }
  static PoseLayout of(const BodyModel& model, bool with_offsets);
};

// Intermediate values the adjoint needs.
struct PoseTrace {
  std::vector<glm::dvec3> rest;                   // V, rest pose with shape and offsets (animal frame)
  std::vector<glm::dvec3> joints;                 // J, shaped joint positions
  std::vector<glm::dmat4> local, global, skin;    // J
  std::vector<glm::dvec3> animal;                 // V, posed (animal frame)
  std::vector<glm::dvec3> world;                  // V, placed (fit frame)
  glm::dmat3 rotation{1.0};
  double scale = 1.0;
  glm::dvec3 translation{0.0};
};

glm::dmat3 rodrigues(const glm::dvec3& axis_angle);

PoseTrace pose_forward(const BodyModel& model, const PoseLayout& layout, const std::vector<double>& x);

// Adds dL/dx to `grad` (size layout.size()) given dL/dworld per vertex.
void pose_backward(const BodyModel& model, const PoseLayout& layout, const std::vector<double>& x,
                   const PoseTrace& trace, const std::vector<glm::dvec3>& d_world, std::vector<double>& grad);

}  // namespace nf::body
