#include "engine/knowledge/metric_scale.hpp"

#include <cmath>
#include <sstream>

#include "engine/core/error.hpp"

namespace nf::knowledge {

MetricScale metric_scale(double eye_cm, double eye_units, std::optional<double> scene_declared, std::optional<double> user_given) {
  MetricScale s;
  if (std::isfinite(eye_cm) && std::isfinite(eye_units) && eye_cm > 0 && eye_units > 0) s.from_eyes = eye_cm / eye_units;
  if (user_given) s.cm_per_unit = *user_given, s.source = "--scene-scale";
  else if (scene_declared) s.cm_per_unit = *scene_declared, s.source = "scene";
  else if (s.from_eyes) s.cm_per_unit = *s.from_eyes, s.source = "eyes";
  if (!(std::isfinite(s.cm_per_unit) && s.cm_per_unit > 0))
    throw InputError("knowledge: no metric scale: the fitted body's eyes are " + std::to_string(eye_units) +
                     " scene units apart and the eye distance is " + std::to_string(eye_cm) +
                     " cm; give the scale with --scene-scale CM_PER_UNIT");
  if (s.from_eyes && s.source != "eyes") {
    s.disagreement = s.cm_per_unit / *s.from_eyes - 1.0;
    if (std::fabs(*s.disagreement) > 0.2) {
      std::ostringstream m;
      m << "the scale from " << (s.source == "scene" ? "the scene file" : "--scene-scale") << " (" << s.cm_per_unit
        << " cm per unit) and the one from the eyes (" << *s.from_eyes << ": " << eye_cm << " cm over " << eye_units
        << " units) differ by " << std::lround(100.0 * std::fabs(*s.disagreement))
        << " %; check the scene's unit or the knowledge's eye_distance_cm";
      s.warning = m.str();
    }
  }
  return s;
}

json to_json(const MetricScale& s) {
  json j{{"cm_per_unit", s.cm_per_unit}, {"source", s.source}};
  j["from_eyes"] = s.from_eyes ? json(*s.from_eyes) : json();
  if (s.disagreement) j["disagreement"] = *s.disagreement;
  if (!s.warning.empty()) j["warning"] = s.warning;
  return j;
}

}  // namespace nf::knowledge
