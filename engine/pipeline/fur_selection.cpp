#include "engine/pipeline/fur_selection.hpp"

#include <cstdio>

#include "engine/metrics/surface_metrics.hpp"
#include "engine/pipeline/fur_evaluation.hpp"
#include "engine/pipeline/fur_stage.hpp"

namespace nf::pipeline {

json to_json(const GroomSignals& g) {
  json j{{"tips_to_envelope_mm", g.tips_to_envelope_mm}, {"envelope_to_tips_mm", g.envelope_to_tips_mm}, {"envelope_mm", g.envelope_mm()}};
  if (g.held_out) j["held_out"] = {{"silhouette_iou", g.silhouette_iou}, {"orientation_error_deg", g.orientation_error_deg}};
  return j;
}

GroomChoice choose_groom(const GroomSignals& warm, const GroomSignals& trained, const GroomChoiceTolerances& tol) {
  char why[300];
  const bool held = warm.held_out && trained.held_out;
  const double env_w = warm.envelope_mm(), env_t = trained.envelope_mm();
  // Relative changes, so that the two signals trade on one scale: the share of the envelope chamfer
  // added and the share of the held-out orientation error removed.
  const double env_loss = env_w > 0 ? env_t / env_w - 1 : 0;
  const double orientation_gain = held && warm.orientation_error_deg > 0 ? 1 - trained.orientation_error_deg / warm.orientation_error_deg : 0;
  const double env_allowed = tol.envelope_allowed(held);
  if (env_loss > env_allowed + 1e-9 && !(orientation_gain > env_loss)) {
    std::snprintf(why, sizeof why, "the image steps moved the tips off M_NeuS (chamfer %.2f mm against %.2f: +%.0f %%, %.0f %% allowed)", env_t,
                  env_w, 100 * env_loss, 100 * env_allowed);
    return {false, why};
  }
  if (held && trained.silhouette_iou < warm.silhouette_iou - tol.iou) {
    std::snprintf(why, sizeof why, "the held-out silhouette got worse (IoU %.3f against %.3f)", trained.silhouette_iou, warm.silhouette_iou);
    return {false, why};
  }
  if (held && trained.orientation_error_deg > warm.orientation_error_deg + tol.orientation_deg) {
    std::snprintf(why, sizeof why, "the held-out orientation got worse (%.2f deg against %.2f)", trained.orientation_error_deg,
                  warm.orientation_error_deg);
    return {false, why};
  }
  const bool gains = env_t < env_w * (1 - tol.envelope) ||
                     (held && (trained.silhouette_iou > warm.silhouette_iou + tol.iou ||
                               trained.orientation_error_deg < warm.orientation_error_deg - tol.orientation_deg));
  if (!gains) return {false, "the image steps gained on no signal beyond its tolerance"};
  const char* trade = env_loss > env_allowed + 1e-9  ? ": the orientation's gain outweighs the chamfer's loss"
                      : env_loss > tol.envelope + 1e-9 ? ": a loss at M_NeuS the photos' resolution of the fur allows"
                                                       : "";
  if (held)
    std::snprintf(why, sizeof why, "held-out IoU %.3f (against %.3f), orientation %.2f deg (%.2f), M_NeuS chamfer %.2f mm (%.2f)%s",
                  trained.silhouette_iou, warm.silhouette_iou, trained.orientation_error_deg, warm.orientation_error_deg, env_t, env_w, trade);
  else
    std::snprintf(why, sizeof why, "M_NeuS chamfer %.2f mm (against %.2f); no held-out view", env_t, env_w);
  return {true, why};
}

GroomSignals measure_groom(fur::FurTrainer& trainer, const fur::FurTrainingData& data, const io::Scene& scene, const geometry::Mesh& envelope,
                           const FurSettings& s, double cm, metrics::StrandSample* grown) {
  GroomSignals g;
  if (!data.held_out.empty()) {
    const std::uint32_t scored = s.score_strands ? s.score_strands : s.training.strands;
    const HeldOutScores h = score_field_held_out(trainer, data.scored_views(), scene, scored, s.training.seed + 7, nullptr);
    g.held_out = true, g.silhouette_iou = h.silhouette_iou, g.orientation_error_deg = h.orientation_error_deg;
  }
  metrics::StrandSample sample =
      metrics::sample_strands(field_strands(trainer, data.roots, s.metric_strands, s.training.seed + 17), s.metric_strands, s.metric_points, 1);
  const metrics::TipChamfer tips = metrics::tip_chamfer(sample, envelope, cm);
  g.tips_to_envelope_mm = tips.tips_to_surface_mm, g.envelope_to_tips_mm = tips.surface_to_tips_mm;
  if (grown) *grown = std::move(sample);
  return g;
}

}  // namespace nf::pipeline
