#pragma once
// The paper's strand metrics (supplementary "Metrics"): precision / recall / F-score between
// points-with-directions of predicted and true strands, and the unsupervised consistency metrics
// of a prediction alone. Lengths are reported in cm through the scene scale (cm per scene unit).
#include <cstdint>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/io/strands.hpp"

namespace nf::metrics {

// Strands resampled to `points` points each, uniformly along their arc length: the metrics compare
// strands point by point, so every strand gets the same count whatever the file had.
struct StrandSample {
  std::uint32_t strands = 0;
  std::uint32_t points = 0;
  std::vector<float> xyz;  // strands * points * 3
};

// At most `max_strands` strands (a seeded random subset when there are more), `points` per strand.
// Strands without length (one point, or all points equal) carry no direction and are skipped.
StrandSample sample_strands(const io::StrandSet& set, std::uint32_t max_strands, std::uint32_t points, unsigned seed);

struct MatchThreshold {
  double distance_cm;
  double angle_deg;
};

struct MatchScore {
  MatchThreshold threshold;
  bool directed;  // directed: strands have a root, so b and -b differ; undirected: angle mod 180
  double precision, recall, fscore;  // percent
};

// A point matches when some point of the other set lies within the distance and their segment
// directions differ by less than the angle (a ball query per point, as the reference evaluation of
// Gaussian Haircut does; it stops at the first match, so good predictions are fast).
std::vector<MatchScore> match_scores(const StrandSample& predicted, const StrandSample& truth,
                                     const std::vector<MatchThreshold>& thresholds, double cm_per_unit);

struct ConsistencyMetrics {
  double length_mean_cm = 0, length_std_cm = 0, local_length_std_cm = 0;
  double curvature_var_global = 0, curvature_var_local = 0, max_bending_deg = 0;
  double direction_var_local = 0, first_direction_var_local = 0;
};

// Local terms average over each strand's `neighbours` nearest roots.
ConsistencyMetrics consistency_metrics(const StrandSample& sample, double cm_per_unit, std::uint32_t neighbours = 10);

std::vector<MatchThreshold> default_thresholds();  // (2 cm, 20 deg), (3 cm, 30 deg), (4 cm, 40 deg)
json to_json(const std::vector<MatchScore>& scores);
json to_json(const ConsistencyMetrics& metrics);

}  // namespace nf::metrics
