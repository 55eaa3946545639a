#include "engine/metrics/groom_scores.hpp"

#include <cmath>
#include <cstdio>

#include "engine/metrics/surface_metrics.hpp"

namespace nf::metrics {

std::vector<MatchThreshold> groom_thresholds() {
  return {{2.0, 20.0}, {3.0, 30.0}, {4.0, 40.0}, {0.2, 20.0}, {0.3, 30.0}, {0.4, 40.0}};
}

std::string threshold_key(const MatchThreshold& t) {
  char key[64];
  if (t.distance_cm >= 1.0)
    std::snprintf(key, sizeof key, "%gcm_%gdeg", t.distance_cm, t.angle_deg);
  else
    std::snprintf(key, sizeof key, "%gmm_%gdeg", std::round(t.distance_cm * 100.0) / 10.0, t.angle_deg);
  return key;
}

json groom_scores(const StrandSample& groom, const GroomTruth& truth, double cm_per_unit) {
  json out{{"strands", groom.strands}, {"consistency", to_json(consistency_metrics(groom, cm_per_unit))}};
  if (truth.strands) {
    const std::vector<MatchScore> scores = match_scores(groom, *truth.strands, groom_thresholds(), cm_per_unit);
    json f = json::object();
    for (const MatchScore& s : scores)
      if (s.directed) f[threshold_key(s.threshold)] = s.fscore;
    out["fscore"] = f;
    out["match"] = to_json(scores);
  }
  if (truth.outer) out["tips_to_outer"] = to_json(tip_chamfer(groom, *truth.outer, cm_per_unit));
  return out;
}

}  // namespace nf::metrics
