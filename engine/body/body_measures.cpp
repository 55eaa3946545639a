#include "engine/body/body_measures.hpp"

#include <algorithm>
#include <array>

namespace nf::body {

std::optional<HeadAxis> head_axis(const BodyModel& model, const std::vector<glm::dvec3>& joints) {
  const int head = model.joint_index("head"), muzzle = model.joint_index("muzzle");
  if (head < 0 || muzzle < 0 || std::size_t(std::max(head, muzzle)) >= joints.size()) return std::nullopt;
  const glm::dvec3 forward = joints[std::size_t(muzzle)] - joints[std::size_t(head)];
  if (!(glm::length(forward) > 0)) return std::nullopt;
  return HeadAxis{joints[std::size_t(head)], glm::normalize(forward)};
}

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
