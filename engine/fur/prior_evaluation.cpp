#include "engine/fur/prior_evaluation.hpp"

#include <cmath>

#include "engine/body/body_model.hpp"
#include "engine/body/quadruped.hpp"
#include "engine/fur/prior_training.hpp"
#include "engine/fur/strand_shapes.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/synth/fur_growth.hpp"

namespace nf::fur {

std::vector<float> synth_strands_in_frames(const std::string& animal, std::uint32_t count, unsigned seed) {
  const body::QuadrupedProportions p = body::animal_proportions(animal);
  const geometry::Mesh skin = body::pose_body(body::build_quadruped(p, {p.torso_length / 70}), {});
  synth::GrowOptions o;
  o.strand_count = count, o.points_per_strand = kStrandPoints, o.seed = seed, o.animal = animal, o.torso_length = p.torso_length;
  const synth::Fur fur = synth::grow_fur(skin, knowledge::preset(animal), synth::fur_style(animal), o);
  std::vector<float> out;
  out.reserve(std::size_t(count) * kStrandPoints * 3);
  std::vector<float> one(kStrandPoints * 3);
  for (std::uint32_t k = 0; k < fur.strands.strand_count(); ++k) {
    const std::uint32_t first = fur.strands.offsets[k], points = fur.strands.points_in(k);
    const float* xyz = &fur.strands.points[std::size_t(first) * 3];
    const glm::vec3 root(xyz[0], xyz[1], xyz[2]), tip(xyz[3 * (points - 1)], xyz[3 * (points - 1) + 1], xyz[3 * (points - 1) + 2]);
    const glm::vec3 n = glm::normalize(fur.root_normals[k]);
    glm::vec3 t = (tip - root) - n * glm::dot(tip - root, n);
    t = glm::length(t) > 1e-9f ? glm::normalize(t) : glm::normalize(glm::cross(n, std::fabs(n.z) < 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0)));
    if (strand_in_frame(xyz, points, root, t, glm::cross(n, t), n, one.data())) out.insert(out.end(), one.begin(), one.end());
  }
  return out;
}

json evaluate_prior(StrandPrior& prior, std::uint32_t n, std::uint32_t fit_iterations, std::uint64_t seed) {
  json sets = json::object();
  double synth_fit = 0;
  const auto measure = [&](const std::string& name, const std::vector<float>& strands) {
    const PointError encoded = reconstruction_error(prior, strands);
    const LatentFit fit = fit_latents(prior, strands, fit_iterations, 0.01f, true);
    sets[name] = {{"strands", strands.size() / (3 * kStrandPoints)},
                  {"encode_decode", {{"mean", encoded.mean}, {"p95", encoded.p95}}},
                  {"fitted", {{"mean", fit.error.mean}, {"p95", fit.error.p95}}}};
    return fit.error.mean;
  };
  // Held-out seeds: far from the training seeds (seed * 1000003 + step).
  for (const StrandStyle style : strand_styles())
    measure(style_name(style), generate_strands(n, 0xE7A1ull * 1000003ull + seed * 31 + std::uint64_t(style), style));
  for (const char* animal : {"cat", "dog", "lion"}) synth_fit += measure(std::string("synth_") + animal, synth_strands_in_frames(animal, n, 5));
  return {{"sets", sets},
          {"synth_fitted_mean", synth_fit / 3},
          {"fit_iterations", fit_iterations},
          {"unit", "mean distance between corresponding points, as a share of the strand's length"}};
}

}  // namespace nf::fur
