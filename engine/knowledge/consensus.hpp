#pragma once
// Consensus of several annotations of the same animal (`knowledge.samples=K`): per region the
// median length and thickness and the normalised mean direction, with the spread of the answers;
// a region whose lengths disagree by more than a factor of two, that is bald in one answer and
// furred in another, or (when furred) whose directions disagree (mean resultant below 0.5) is flagged. A region (mane) is kept when more than half of the answers have it.
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/knowledge/knowledge.hpp"

namespace nf::knowledge {

struct Consensus {
  Knowledge knowledge;
  json spread;                        // {"<region>": {"length_cm": [min, max], "thickness_cm": [..], "direction_agreement": r}, "eye_distance_cm": [..]}
  std::vector<std::string> flagged;  // regions whose answers disagree by more than 2x
};

// `samples` non-empty; the result's animal and source are the first sample's.
Consensus consensus(const std::vector<Knowledge>& samples);

}  // namespace nf::knowledge
