#pragma once
// Surface metrics on sampled points (the paper's supplementary, Metrics): two-way chamfer (mean / min / max over both
// directions' nearest distances, and each direction's mean), normal consistency and F-score at a
// distance, in mm through the scene scale; and the two-way chamfer between strand tips and the
// outer surface (the paper's CD).
#include <cstdint>

#include "engine/core/json.hpp"
#include "engine/io/mesh.hpp"
#include "engine/metrics/strand_metrics.hpp"

namespace nf::metrics {

struct SurfaceMetrics {
  std::uint64_t samples = 0;
  double chamfer_mean_mm = 0, chamfer_min_mm = 0, chamfer_max_mm = 0;
  double accuracy_mm = 0;      // mean distance from the mesh to the reference
  double completeness_mm = 0;  // mean distance from the reference to the mesh
  double normal_consistency = 0;  // mean |n . n_nearest| over both directions, 1 is best
  double fscore_threshold_mm = 0, precision = 0, recall = 0, fscore = 0;  // percent
};

SurfaceMetrics surface_metrics(const geometry::Mesh& mesh, const geometry::Mesh& reference, double cm_per_unit,
                               double fscore_threshold_mm = 5.0, std::uint64_t samples = 100000, unsigned seed = 1);

struct TipChamfer {
  double tips_to_surface_mm = 0, surface_to_tips_mm = 0, two_way_mm = 0;
};

// Strand tips (last points) against points sampled on the outer surface.
TipChamfer tip_chamfer(const StrandSample& strands, const geometry::Mesh& outer, double cm_per_unit,
                       std::uint64_t samples = 100000, unsigned seed = 1);

json to_json(const SurfaceMetrics& metrics);
json to_json(const TipChamfer& metrics);

}  // namespace nf::metrics
