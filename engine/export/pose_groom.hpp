#pragma once
// Posing the exported animal with its skeleton: linear blend skinning of the body, and each strand
// moved rigidly with the frame of the body face its root sits on (so strands keep their shape and
// stay rooted in the skin while the body bends). Rotations are rotation vectors (axis x angle) in
// the export frame, applied at each joint in the bind pose (whose joints carry no rotation).
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "engine/geometry/mesh.hpp"
#include "engine/io/skeleton.hpp"

namespace nf::exporter {

// Per joint: posed global transform times the inverse bind matrix (rest -> posed). `rotations` has
// one rotation vector (radians) per joint; missing entries are no rotation.
std::vector<glm::mat4> skinning_transforms(const io::Skeleton& skeleton, const std::vector<glm::vec3>& rotations);

// The mesh moved by the skeleton (positions and normals; regions kept).
geometry::Mesh skin_mesh(const geometry::Mesh& rest, const io::Skeleton& skeleton, const std::vector<glm::mat4>& skinning);

// How a strand rooted at (face, barycentric) moves when `rest` becomes `posed` (same topology).
struct RootMotion {
  glm::mat3 rotation{1.f};
  glm::vec3 from{0.f}, to{0.f};
  glm::vec3 apply(const glm::vec3& p) const { return to + rotation * (p - from); }
};
RootMotion root_motion(const geometry::Mesh& rest, const geometry::Mesh& posed, std::uint32_t face, const glm::vec3& barycentric);

}  // namespace nf::exporter
