#pragma once
// A skeleton bound to a mesh for linear blend skinning, as the body export writes it into glTF:
// joints in a parent-before-child order, their positions in the bind pose (the mesh's frame, no
// rest rotations), and four joint influences per vertex.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace nf::io {

inline constexpr int kJointInfluences = 4;

struct Skeleton {
  std::vector<std::string> joint_names;
  std::vector<std::int32_t> parents;        // -1 for a root; a parent comes before its children
  std::vector<glm::vec3> joint_positions;   // bind pose
  std::vector<std::uint16_t> skin_joints;   // vertices x 4
  std::vector<float> skin_weights;          // vertices x 4, each row sums to 1

  std::size_t joint_count() const { return joint_names.size(); }
  // InputError naming `source` and the field: sizes, parent order, joint indices, weights.
  void validate(const std::string& source, std::size_t vertices) const;
};

}  // namespace nf::io
