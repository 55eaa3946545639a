#pragma once
// The metric scale (cm per scene unit) that turns the knowledge's centimetres into scene units:
// `--scene-scale` when given, else the scene's declared unit, else the paper's estimate from the
// eyes: the knowledge's eye distance (cm) over the fitted body's eye distance (scene units). When
// the eye estimate and a given scale both exist both are reported, and a disagreement of more
// than 20 % is a warning (wrong units, or a wrong eye distance).
#include <optional>
#include <string>

#include "engine/core/json.hpp"

namespace nf::knowledge {

struct MetricScale {
  double cm_per_unit = 0;
  std::string source;                  // "--scene-scale", "scene", or "eyes"
  std::optional<double> from_eyes;     // the estimate from the eyes, when the body has eyes
  std::optional<double> disagreement;  // given / from_eyes - 1, when both exist
  std::string warning;                 // non-empty when they disagree by more than 20 %
};

// Throws InputError when no source gives a finite positive scale.
MetricScale metric_scale(double eye_distance_cm, double eye_distance_units, std::optional<double> scene_declared,
                         std::optional<double> user_given);
json to_json(const MetricScale& scale);

}  // namespace nf::knowledge
