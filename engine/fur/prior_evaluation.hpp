#pragma once
// Measuring the strand prior on fur it was not trained on: `nf_gpu synth`'s grown strands. Apart
// from prior_training.hpp (and in its own library) because it grows fur with engine/synth, which
// the fur stage never needs.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/fur/strand_prior.hpp"

namespace nf::fur {

// Ground-truth strands of `nf_gpu synth`'s fur for `animal` (grown on its body as synth grows
// them, no rendering), each moved into its root's frame (N: the skin's normal, T: the strand's
// heading on the skin) and made unit length: N x 100 x 3.
std::vector<float> synth_strands_in_frames(const std::string& animal, std::uint32_t count, unsigned seed);

// The evaluation the README and the record report: held-out strands of every style and synth fur
// of the cat, dog and lion; mean and 95th percentile point error after encoding and after fitting.
json evaluate_prior(StrandPrior& prior, std::uint32_t strands_per_set, std::uint32_t fit_iterations, std::uint64_t seed);

}  // namespace nf::fur
