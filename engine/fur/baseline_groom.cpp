#include "engine/fur/baseline_groom.hpp"

#include <cmath>

namespace nf::fur {

io::StrandSet baseline_groom(const Roots& roots, const std::vector<std::uint32_t>& ids, double lying_angle_deg,
                             std::uint32_t points_per_strand) {
  const double a = lying_angle_deg * M_PI / 180.0;
  std::vector<float> xyz;
  xyz.reserve(ids.size() * points_per_strand * 3);
  for (std::uint32_t r : ids) {
    const glm::vec3 n = roots.normal[r];
    glm::vec3 d = roots.direction[r] - glm::dot(roots.direction[r], n) * n;
    d = glm::length(d) > 1e-6f ? glm::normalize(d) : roots.tangent[r];
    const glm::vec3 heading = float(std::cos(a)) * d + float(std::sin(a)) * n;
    for (std::uint32_t k = 0; k < points_per_strand; ++k) {
      const glm::vec3 p = roots.position[r] + heading * (roots.length[r] * float(k) / float(points_per_strand - 1));
      xyz.insert(xyz.end(), {p.x, p.y, p.z});
    }
  }
  io::StrandSet set = io::StrandSet::uniform(std::uint32_t(ids.size()), points_per_strand, std::move(xyz));
  for (std::uint32_t r : ids) set.regions.push_back(std::uint16_t(std::max(0, roots.region[r])));
  return set;
}

}  // namespace nf::fur
