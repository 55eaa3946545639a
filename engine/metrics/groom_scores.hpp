#pragma once
// One groom's scores as the fur stage and its bench report them (issue: Speed against error): the
// unsupervised consistency metrics, and against ground truth the directed F-scores at the paper's
// (2, 3, 4 cm; 20, 30, 40 deg) and at (2, 3, 4 mm; same angles) — the cm thresholds say "the fur is
// on the right surface, pointing roughly the right way", the mm ones see the body's accuracy and
// the strands' shape — and the strand-tip chamfer to the outer surface.
#include <string>

#include "engine/core/json.hpp"
#include "engine/geometry/mesh.hpp"
#include "engine/metrics/strand_metrics.hpp"

namespace nf::metrics {

struct GroomTruth {
  const StrandSample* strands = nullptr;  // ground-truth strands, sampled like the groom
  const geometry::Mesh* outer = nullptr;  // the fur envelope
};

std::vector<MatchThreshold> groom_thresholds();  // the six above

// {"consistency": {...}, ["fscore": {"2cm_20deg": F, ..., "4mm_40deg": F}, "match": [...]],
//  ["tips_to_outer": {...}]}
json groom_scores(const StrandSample& groom, const GroomTruth& truth, double cm_per_unit);

// "2cm_20deg" and alike: the key of a threshold in groom_scores' "fscore".
std::string threshold_key(const MatchThreshold& t);

}  // namespace nf::metrics
