#pragma once
// `nf_gpu metrics` as data: which unit the files are in, which thresholds apply, and the JSON
// report of strand or surface metrics. The CLI only parses arguments and prints this.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/metrics/strand_metrics.hpp"

namespace nf::metrics {

struct MetricsRequest {
  std::filesystem::path pred, gt, outer;  // strands: predicted, ground truth, outer surface for tips
  std::filesystem::path mesh, reference;  // surfaces
  std::optional<double> scale;            // cm per scene unit, when the user gives it (--scale)
  std::string thresholds = "cm";          // "cm" (the paper's), "mm" (hair papers'), or "2cm:20,5mm:10"
  double fscore_mm = 5.0;                 // surface F-score distance
  std::uint32_t strands = 100000, points = 100;
  unsigned seed = 1;
};

// The unit (cm per scene unit) the files declare: a `scale.json` ({"cm_per_unit": x}) beside any
// of them, or an `nf_gpu synth` scene's gt/scene.json beside them. nullopt when none does;
// InputError when two declarations disagree or one is malformed. `source` names the file used.
std::optional<double> declared_scale(const std::vector<std::filesystem::path>& files, std::string* source = nullptr);

// --scale when given (a declared scale that differs is reported in the warning log), else 100
// when the files are in the export frame (`metres`: it is in metres), else the declared one, else
// UsageError: nf_gpu never guesses a unit.
double resolve_scale(const MetricsRequest& request, std::string* source, bool metres = false);

// "cm" -> (2 cm, 20 deg), (3 cm, 30), (4 cm, 40); "mm" -> (2 mm, 20), (3 mm, 30), (4 mm, 40);
// otherwise comma-separated DISTANCE:ANGLE with a unit on the distance (mm, cm, m), e.g.
// "2cm:20,5mm:10". UsageError naming the bad entry.
std::vector<MatchThreshold> parse_thresholds(const std::string& text);

// {pred, strands, points_per_strand, cm_per_unit, scale_source, consistency, [gt, match], [tips_to_outer]}
json strand_report(const MetricsRequest& request);
// {mesh, reference, cm_per_unit, scale_source, surface}
json surface_report(const MetricsRequest& request);

}  // namespace nf::metrics
