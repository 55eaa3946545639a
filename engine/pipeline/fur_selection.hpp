#pragma once
// Never worse than the warm start: the fur stage keeps what its steps made only where the data it
// has says they helped. The candidates, in order: the 0-step groom (the warm start), the field when
// the warm-up ended (the knowledge, M_bald and M_NeuS alone) and the trained field; each replaces
// the one kept so far only when choose_groom says so. Each is measured on what the stage has
// without a ground truth:
//   - the held-out views: silhouette IoU and the reliability-weighted orientation error;
//   - M_NeuS, the envelope of the fur: the two-way chamfer between the strands' tips and M_NeuS
//     (tips far outside it are fur where the photos show none; M_NeuS far from every tip is fur
//     that does not reach where they show some).
// The held-out orientation error alone can improve while the groom gets worse (docs/fur-stage.md),
// so a later groom must not lose on any signal beyond a tolerance, and must gain on at least one;
// except that a loss at M_NeuS is accepted when the held-out orientation error falls by a larger
// share than the envelope chamfer grows: a wrong growth direction that the photos correct turns
// every strand and moves their tips off M_NeuS a little, where strands lifted off the fur move the
// tips far more than they gain in orientation (docs/fur-stage.md has both cases).
// How much the chamfer may grow follows how well the training photos resolve the fur (the image
// losses' own weight): M_NeuS is a reconstruction too, and where the photos show the fur the
// held-out views are the nearer witness. Measured: where the fur spans 5.8-6.5 photo pixels the
// trained grooms that gained 1.4-3.7 points at 2 mm had moved the chamfer 8-16 %; on the demo
// (2.9 px, weight 0.19) the one that lost 6.7 points had moved it 35 %.
#include <string>

#include "engine/core/json.hpp"
#include "engine/fur/fur_trainer.hpp"
#include "engine/geometry/mesh.hpp"
#include "engine/io/scene.hpp"
#include "engine/metrics/strand_metrics.hpp"

namespace nf::pipeline {

struct FurSettings;

struct GroomSignals {
  bool held_out = false;  // held-out views were scored
  double silhouette_iou = 0, orientation_error_deg = 0;
  double tips_to_envelope_mm = 0, envelope_to_tips_mm = 0;
  double envelope_mm() const { return 0.5 * (tips_to_envelope_mm + envelope_to_tips_mm); }
};
json to_json(const GroomSignals& g);

struct GroomChoiceTolerances {
  double iou = 0.01;       // held-out silhouette IoU the trained groom may lose
  double envelope = 0.05;  // share of the envelope chamfer it may add
  double orientation_deg = 0.25;  // held-out orientation error it may add
  // Share of the envelope chamfer it may add beyond `envelope` when held-out views were scored,
  // times `image_weight`: the training views' mean image weight (0-1, fur_resolution.hpp).
  double envelope_resolved = 0.20;
  double image_weight = 0;
  double envelope_allowed(bool held_out) const { return envelope + (held_out ? envelope_resolved * image_weight : 0); }
};

struct GroomChoice {
  bool trained = true;
  std::string reason;
};
// Whether `trained` (the later candidate) replaces `warm` (the one kept so far).
GroomChoice choose_groom(const GroomSignals& warm, const GroomSignals& trained, const GroomChoiceTolerances& tol = {});

// A candidate's signals: the trainer's field as it is now, rendered into the held-out views at the
// scored strands' count and grown at metric_strands roots against `envelope` (M_NeuS); `grown`,
// when given, receives that sample of the strands (for scores against a ground truth).
GroomSignals measure_groom(fur::FurTrainer& trainer, const fur::FurTrainingData& data, const io::Scene& scene,
                           const geometry::Mesh& envelope, const FurSettings& s, double cm, metrics::StrandSample* grown = nullptr);

}  // namespace nf::pipeline
