#pragma once
// The metric scale (cm per scene unit) that turns the knowledge's centimetres into scene units.
// `--scene-scale` when given, else the scene's declared unit; else the cues the animal gives,
// combined: the knowledge's eye distance over the fitted eyes' distance (the paper's estimate) and
// the knowledge's head-and-body length over the fitted body's. Each cue carries how far it may be
// off (a relative spread); the combination is their weighted mean in log space, with its own
// spread (widened when the cues disagree beyond theirs). Cues that disagree by more than their
// spreads allow, or a given scale that a cue contradicts by more than 20 %, are warnings (wrong
// units, an unusual individual, a poor fit).
#include <optional>
#include <string>
#include <vector>

#include "engine/core/json.hpp"

namespace nf::knowledge {

// How far each cue may be off, relative (one standard deviation of its log). The eyes: an
// individual's eye distance differs from its kind's by about 10 %, and the fitted template's eyes
// of animals nf_gpu never made were 20-40 % too far apart (issue 42's measurements). Eyes
// triangulated in the photos are within 12 % of their true distance on 16 of the body bench's
// eighteen bodies at 256 px (17 % RMS: a face the fit missed, a stripe taken for an eye), so what
// their spread must also cover is the individual: 10 % or more from its
// kind (the bench's animals, drawn 25 % from their families, were up to 47 % off, and a spread of
// 12 % took the combined scale from 14 % to 19 % RMS there). The body length: adults of a kind
// differ by about 15 %, and a fit's skeleton follows the surface to a few percent.
inline constexpr double kEyeCueSpread = 0.25, kPhotoEyeCueSpread = 0.18, kBodyLengthCueSpread = 0.15;

struct ScaleCue {
  std::string name;        // "eyes" or "body length"
  double cm_per_unit = 0;
  double spread = 0;       // relative
  std::string detail;      // what it divides, for people
};

struct ScaleInputs {
  double eye_distance_cm = 0, eye_distance_units = 0;
  bool eyes_from_photos = false;  // triangulated in the photos (else the fitted template's)
  std::optional<double> body_length_cm, body_length_units;
  std::optional<double> scene_declared, user_given;
};

struct MetricScale {
  double cm_per_unit = 0;
  std::string source;                  // "--scene-scale", "scene", "eyes", "body length" or "eyes + body length"
  double spread = 0;                   // relative; 0 for a given or declared unit
  double cues_spread = 0;              // the cues' combination's, relative (when there is one)
  std::vector<ScaleCue> cues;          // every cue the animal gave
  std::optional<double> from_eyes;     // the eyes' estimate, when the body has eyes
  std::optional<double> from_cues;     // the cues combined, when there is any
  std::optional<double> disagreement;  // given / from_cues - 1, when both exist
  std::string warning;                 // non-empty when cues or a given scale disagree beyond the spreads
};

// Throws InputError when no source gives a finite positive scale.
MetricScale metric_scale(const ScaleInputs& inputs);
json to_json(const MetricScale& scale);

}  // namespace nf::knowledge
