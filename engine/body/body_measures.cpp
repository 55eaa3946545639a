#include "engine/body/body_measures.hpp"

#include <array>

namespace nf::body {

std::optional<double> head_and_body_length(const BodyModel& model, const std::vector<glm::dvec3>& joints) {
  static constexpr std::array<const char*, 8> kPath = {"nose", "muzzle", "head", "neck", "chest", "spine", "pelvis", "tail_0"};
  double length = 0;
  std::optional<glm::dvec3> previous;
  for (const char* name : kPath) {
    const int j = model.joint_index(name);
    if (j < 0 || std::size_t(j) >= joints.size()) return std::nullopt;
    if (previous) length += glm::distance(*previous, joints[std::size_t(j)]);
    previous = joints[std::size_t(j)];
  }
  return length;
}

}  // namespace nf::body
