#include "engine/io/skeleton.hpp"

#include <cmath>

#include "engine/core/error.hpp"

namespace nf::io {

void Skeleton::validate(const std::string& source, std::size_t vertices) const {
  const std::size_t J = joint_count();
  const auto fail = [&](const std::string& what) { throw InputError(source + ": skeleton " + what); };
  if (J == 0) fail("has no joints");
  if (J > 65535) fail("has " + std::to_string(J) + " joints; 65535 at most");
  if (parents.size() != J || joint_positions.size() != J) fail("parents / joint_positions do not have one entry per joint");
  for (std::size_t j = 0; j < J; ++j) {
    if (parents[j] >= std::int32_t(j) || parents[j] < -1) fail("joint '" + joint_names[j] + "' has parent " + std::to_string(parents[j]) + ", not an earlier joint");
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(joint_positions[j][a])) fail("joint '" + joint_names[j] + "' has a non-finite position");
  }
  if (skin_joints.size() != kJointInfluences * vertices || skin_weights.size() != kJointInfluences * vertices)
    fail("influences: " + std::to_string(skin_weights.size() / kJointInfluences) + " rows for " + std::to_string(vertices) + " vertices");
  for (std::size_t v = 0; v < vertices; ++v) {
    double sum = 0;
    for (int k = 0; k < kJointInfluences; ++k) {
      const float w = skin_weights[kJointInfluences * v + std::size_t(k)];
      if (!(w >= 0 && w <= 1)) fail("weight of vertex " + std::to_string(v) + " is " + std::to_string(w) + ", not in [0, 1]");
      if (skin_joints[kJointInfluences * v + std::size_t(k)] >= J) fail("vertex " + std::to_string(v) + " names joint " + std::to_string(skin_joints[kJointInfluences * v + std::size_t(k)]));
      sum += w;
    }
    if (std::abs(sum - 1.0) > 1e-3) fail("weights of vertex " + std::to_string(v) + " sum to " + std::to_string(sum) + ", not 1");
  }
}

}  // namespace nf::io
