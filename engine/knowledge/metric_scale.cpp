#include "engine/knowledge/metric_scale.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"

namespace nf::knowledge {
namespace {

bool positive(double v) { return std::isfinite(v) && v > 0; }

std::string percent(double relative) { return std::to_string(std::lround(100.0 * std::fabs(relative))) + " %"; }

std::string describe(const ScaleCue& c) {
  std::ostringstream m;
  m << "the " << c.name << " (" << c.cm_per_unit << ": " << c.detail << ")";
  return m.str();
}

}  // namespace

MetricScale metric_scale(const ScaleInputs& in) {
  MetricScale s;
  if (positive(in.eye_distance_cm) && positive(in.eye_distance_units)) {
    std::ostringstream d;
    d << in.eye_distance_cm << " cm over " << in.eye_distance_units << " units (" << (in.eyes_from_photos ? "the photos'" : "the fit's")
      << " eyes)";
    s.cues.push_back({"eyes", in.eye_distance_cm / in.eye_distance_units, in.eyes_from_photos ? kPhotoEyeCueSpread : kEyeCueSpread, d.str()});
    s.from_eyes = s.cues.back().cm_per_unit;
  }
  if (in.body_length_cm && in.body_length_units && positive(*in.body_length_cm) && positive(*in.body_length_units)) {
    std::ostringstream d;
    d << *in.body_length_cm << " cm of head and body over " << *in.body_length_units << " units";
    s.cues.push_back({"body length", *in.body_length_cm / *in.body_length_units, kBodyLengthCueSpread, d.str()});
  }
  // Inverse-variance weights in log space: the cue that may be off the least counts the most.
  if (!s.cues.empty()) {
    double sum_w = 0, sum = 0;
    std::vector<std::string> names;
    for (const ScaleCue& c : s.cues) {
      const double w = 1.0 / (c.spread * c.spread);
      sum_w += w, sum += w * std::log(c.cm_per_unit);
      names.push_back(c.name);
    }
    s.from_cues = std::exp(sum / sum_w);
    // Cues that disagree beyond their spreads show that those spreads are too small for this animal
    // (an individual far from its kind, a poor fit): the combination's spread grows by the Birge
    // ratio sqrt(chi^2 / (n - 1)), never shrinks, as for inconsistent measurements of one quantity.
    double chi2 = 0;
    for (const ScaleCue& c : s.cues) chi2 += std::pow(std::log(c.cm_per_unit / *s.from_cues) / c.spread, 2);
    const double birge = s.cues.size() > 1 ? std::max(1.0, std::sqrt(chi2 / double(s.cues.size() - 1))) : 1.0;
    s.cues_spread = birge / std::sqrt(sum_w);
    s.spread = s.cues_spread;
    s.source = join(names, " + ");
    s.cm_per_unit = *s.from_cues;
  }
  if (in.user_given) s.cm_per_unit = *in.user_given, s.source = "--scene-scale", s.spread = 0;
  else if (in.scene_declared) s.cm_per_unit = *in.scene_declared, s.source = "scene", s.spread = 0;
  if (!positive(s.cm_per_unit))
    throw InputError("knowledge: no metric scale: the fitted body's eyes are " + std::to_string(in.eye_distance_units) +
                     " scene units apart and the eye distance is " + std::to_string(in.eye_distance_cm) +
                     " cm, and no head-and-body length pairs the knowledge's with the fit's; give the scale with "
                     "--scene-scale CM_PER_UNIT");

  std::vector<std::string> problems;
  if ((in.user_given || in.scene_declared) && s.from_cues) {  // a given unit: each cue checked against it
    s.disagreement = s.cm_per_unit / *s.from_cues - 1.0;
    const std::string given = s.source == "scene" ? "the scene file" : "--scene-scale";
    for (const ScaleCue& c : s.cues) {
      const double off = s.cm_per_unit / c.cm_per_unit - 1.0;
      if (std::fabs(off) > 0.2) {
        std::ostringstream m;
        m << "the scale from " << given << " (" << s.cm_per_unit << " cm per unit) and " << describe(c) << " differ by "
          << percent(off);
        problems.push_back(m.str());
      }
    }
    if (!problems.empty()) problems.back() += "; check the scene's unit or the knowledge's eye_distance_cm and body_length_cm";
  } else {
    // Two cues further apart than their spreads together allow: one of them is wrong.
    for (std::size_t a = 0; a < s.cues.size(); ++a)
      for (std::size_t b = a + 1; b < s.cues.size(); ++b) {
        const ScaleCue &x = s.cues[a], &y = s.cues[b];
        if (std::fabs(std::log(x.cm_per_unit / y.cm_per_unit)) > std::hypot(x.spread, y.spread)) {
          std::ostringstream m;
          m << describe(x) << " and " << describe(y) << " differ by " << percent(x.cm_per_unit / y.cm_per_unit - 1.0)
            << ", more than they may (" << percent(std::hypot(x.spread, y.spread)) << "): the scale " << s.cm_per_unit
            << " may be off by more than its " << percent(s.spread) << "; give --scene-scale if you know it";
          problems.push_back(m.str());
        }
      }
  }
  s.warning = join(problems, "; ");
  return s;
}

json to_json(const MetricScale& s) {
  json cues = json::array();
  for (const ScaleCue& c : s.cues)
    cues.push_back({{"cue", c.name}, {"cm_per_unit", c.cm_per_unit}, {"spread", c.spread}, {"from", c.detail}});
  json j{{"cm_per_unit", s.cm_per_unit}, {"source", s.source}, {"spread", s.spread}, {"cues", cues}};
  j["from_eyes"] = s.from_eyes ? json(*s.from_eyes) : json();
  j["from_cues"] = s.from_cues ? json(*s.from_cues) : json();
  if (s.from_cues) j["cues_spread"] = s.cues_spread;
  if (s.disagreement) j["disagreement"] = *s.disagreement;
  if (!s.warning.empty()) j["warning"] = s.warning;
  return j;
}

}  // namespace nf::knowledge
