#pragma once
// How far an orientation map of a photo can be trusted, judged against the photo's true
// orientation (`nf_gpu synth --true-orientation`: the on-screen direction of the strands each pixel
// shows). The fur stage's orientation loss weighs each pixel by its Gabor reliability
// (orientation_scales.hpp), so the figures that matter are the error where the map is reliable, the
// share of the fur that is, and the error weighted as the loss weighs it.
#include <array>
#include <cstdint>
#include <vector>

#include "engine/orient/orientation_map.hpp"

namespace nf::orient {

struct TruthOptions {
  std::uint32_t outline = 8;       // pixels: no target this near the mask's edge (the fur stage's margin)
  float min_truth_weight = 0.8f;   // scored where the truth's weight is at least this (a strand, agreed on)
  float reliable = 0.5f;           // the reliability from which a pixel counts as reliable
};

struct TruthAgreement {
  std::uint64_t pixels = 0;          // fur pixels scored
  double median_error_deg = 0;       // undirected angle error, over those pixels
  double reliable_share = 0;         // share of them at least `reliable`
  double median_error_reliable_deg = 0;  // over the reliable ones (0 when none is)
  double weighted_error_deg = 0;     // mean error weighted by reliability (0 when no pixel has any)
  double mean_reliability = 0;
  // The median error of the pixels whose reliability lies in [0, 0.2), [0.2, 0.4), ... [0.8, 1]
  // (0 for an empty bin) and each bin's share of the pixels: whether reliability predicts error.
  std::array<double, 5> median_error_by_reliability{}, share_by_reliability{};
};

// `reliability` per pixel of `map` (orientation_reliability). `mask`: the photo's mask (one byte a
// pixel). InputError when the sizes differ; pixels 0 (and every figure 0) when no pixel can be scored.
TruthAgreement agreement_with_truth(const OrientationMap& map, const std::vector<float>& reliability, const OrientationMap& truth,
                                    const std::vector<std::uint8_t>& mask, const TruthOptions& options = {});

}  // namespace nf::orient
