#include "engine/pipeline/preview_views.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace nf::pipeline {

std::vector<std::uint32_t> preview_views(const io::Scene& scene, int count) {
  std::vector<std::uint32_t> views;
  if (scene.cameras.empty() || count <= 0) return views;
  views.push_back(0);
  const glm::dvec3 first = glm::dvec3(scene.cameras[0].camera_to_world[2]);
  while (int(views.size()) < count && views.size() < scene.cameras.size()) {
    std::uint32_t best = 0;
    double best_score = std::numeric_limits<double>::infinity();
    for (std::uint32_t k = 0; k < scene.cameras.size(); ++k) {
      if (std::find(views.begin(), views.end(), k) != views.end()) continue;
      const double score = std::abs(glm::dot(first, glm::normalize(glm::dvec3(scene.cameras[k].camera_to_world[2]))));
      if (score < best_score) best_score = score, best = k;
    }
    views.push_back(best);
  }
  return views;
}

}  // namespace nf::pipeline
