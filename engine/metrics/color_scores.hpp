#pragma once
// The groom's colours against a synthetic scene's true strand colours (gt/strands.hair's colour
// array): each scored strand is matched to the true strand whose root is nearest, and its colour
// at t = 1/C .. 1 compared with the true strand's at the same share of its points, as CIE76 Delta E
// (engine/core/color.hpp). Photos hold the colours lit, the truth the strands' own: one gain on
// the luminance (least squares over the seen strands) takes the light's exposure out before the
// difference. Reported apart for the strands a view saw and those filled from neighbours; for the
// seen ones also by place along the strand, and against the mean colour of the 8 nearest true
// strands (`delta_e_seen_local`: without each strand's own random tint, which no photo resolves).
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/json.hpp"
#include "engine/io/strands.hpp"

namespace nf::metrics {

struct GroomColors {
  std::span<const float> roots;                            // strands x 3, the truth's frame and unit
  std::span<const std::uint8_t> seen;                      // per strand
  std::function<glm::vec3(std::uint64_t strand, float t)> at;  // linear RGB at t in [0, 1]
  std::uint32_t controls = 3;                               // the t's compared: 1/C .. 1
};

// The true strands' roots and their colours at `samples` evenly spaced places from root to tip
// (a few MB where the strands file is hundreds). InputError when `truth` carries no colours.
struct ColorTruth {
  std::uint32_t samples = 0;
  std::vector<float> roots;  // strands x 3
  std::vector<float> rgb;    // strands x samples x 3, linear
  std::size_t strands() const { return roots.size() / 3; }
  glm::vec3 at(std::size_t strand, float t) const;
};
ColorTruth color_truth(const io::StrandSet& truth, std::uint32_t samples = 11);

// At most `max_strands` strands are scored (an even subset). Returns {delta_e_seen, delta_e_unseen (mean, median, p90), delta_e_seen_along,
// delta_e_seen_local, delta_l_seen and delta_ab_seen (its lightness and hue-saturation parts), exposure_gain, strands_scored}.
json color_scores(const GroomColors& groom, const ColorTruth& truth, std::uint32_t max_strands);

}  // namespace nf::metrics
