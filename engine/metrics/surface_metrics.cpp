#include "engine/metrics/surface_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/geometry/surface_sampling.hpp"

namespace nf::metrics {
namespace {

struct Nearest {
  std::vector<double> distance;  // scene units
  std::vector<double> alignment; // |n . n_nearest| (when normals are given)
};

Nearest nearest_to(const std::vector<float>& from, const std::vector<float>& from_normals, const std::vector<float>& to,
                   const std::vector<float>& to_normals) {
  const geometry::PointIndex index(to);
  Nearest n;
  n.distance.resize(from.size() / 3);
  n.alignment.resize(from.size() / 3, 0.0);
  parallel_for(from.size() / 3, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const auto [j, d2] = index.nearest(&from[3 * i]);
      n.distance[i] = std::sqrt(double(d2));
      if (!from_normals.empty() && !to_normals.empty())
        n.alignment[i] = std::fabs(double(from_normals[3 * i]) * to_normals[3 * j] + double(from_normals[3 * i + 1]) * to_normals[3 * j + 1] +
                                   double(from_normals[3 * i + 2]) * to_normals[3 * j + 2]);
    }
  });
  return n;
}

double mean(const std::vector<double>& v) { return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / double(v.size()); }

}  // namespace

SurfaceMetrics surface_metrics(const geometry::Mesh& mesh, const geometry::Mesh& reference, double cm_per_unit,
                               double fscore_threshold_mm, std::uint64_t samples, unsigned seed) {
  if (!(cm_per_unit > 0)) throw InputError("metrics: the scene scale (cm per unit) must be positive");
  const auto a = geometry::sample_surface(mesh, samples, seed), b = geometry::sample_surface(reference, samples, seed);
  if (a.points.empty() || b.points.empty()) throw InputError("surface metrics: a mesh has no area to sample");
  const Nearest ab = nearest_to(a.points, a.normals, b.points, b.normals);
  const Nearest ba = nearest_to(b.points, b.normals, a.points, a.normals);
  const double mm = cm_per_unit * 10.0;
  SurfaceMetrics m;
  m.samples = samples;
  std::vector<double> all = ab.distance;
  all.insert(all.end(), ba.distance.begin(), ba.distance.end());
  m.chamfer_mean_mm = mean(all) * mm;
  m.chamfer_min_mm = *std::min_element(all.begin(), all.end()) * mm;
  m.chamfer_max_mm = *std::max_element(all.begin(), all.end()) * mm;
  m.accuracy_mm = mean(ab.distance) * mm;
  m.completeness_mm = mean(ba.distance) * mm;
  m.normal_consistency = 0.5 * (mean(ab.alignment) + mean(ba.alignment));
  m.fscore_threshold_mm = fscore_threshold_mm;
  const auto within = [&](const std::vector<double>& d) {
    return 100.0 * double(std::count_if(d.begin(), d.end(), [&](double x) { return x * mm <= fscore_threshold_mm; })) /
           double(d.size());
  };
  m.precision = within(ab.distance);
  m.recall = within(ba.distance);
  m.fscore = m.precision + m.recall > 0 ? 2 * m.precision * m.recall / (m.precision + m.recall) : 0.0;
  return m;
}

TipChamfer tip_chamfer(const StrandSample& strands, const geometry::Mesh& outer, double cm_per_unit, std::uint64_t samples,
                       unsigned seed) {
  if (!(cm_per_unit > 0)) throw InputError("metrics: the scene scale (cm per unit) must be positive");
  if (strands.points < 1) throw InputError("tip chamfer: strands have no points");
  std::vector<float> tips;
  for (std::uint32_t i = 0; i < strands.strands; ++i) {
    const std::size_t last = (std::size_t(i) + 1) * strands.points - 1;
    tips.insert(tips.end(), strands.xyz.begin() + std::ptrdiff_t(3 * last), strands.xyz.begin() + std::ptrdiff_t(3 * last + 3));
  }
  const auto surface = geometry::sample_surface(outer, samples, seed);
  TipChamfer c;
  if (surface.points.empty()) throw InputError("tip chamfer: the outer surface has no area to sample");
  if (tips.empty()) throw InputError("tip chamfer: no strands");
  const double mm = cm_per_unit * 10.0;
  c.tips_to_surface_mm = mean(nearest_to(tips, {}, surface.points, {}).distance) * mm;
  c.surface_to_tips_mm = mean(nearest_to(surface.points, {}, tips, {}).distance) * mm;
  c.two_way_mm = 0.5 * (c.tips_to_surface_mm + c.surface_to_tips_mm);
  return c;
}

json to_json(const SurfaceMetrics& m) {
  return {{"samples", m.samples},
          {"chamfer_mm", {{"mean", m.chamfer_mean_mm}, {"min", m.chamfer_min_mm}, {"max", m.chamfer_max_mm}}},
          {"accuracy_mm", m.accuracy_mm},
          {"completeness_mm", m.completeness_mm},
          {"normal_consistency", m.normal_consistency},
          {"fscore", {{"threshold_mm", m.fscore_threshold_mm}, {"precision", m.precision}, {"recall", m.recall}, {"fscore", m.fscore}}}};
}

json to_json(const TipChamfer& c) {
  return {{"tips_to_surface_mm", c.tips_to_surface_mm}, {"surface_to_tips_mm", c.surface_to_tips_mm}, {"two_way_mm", c.two_way_mm}};
}

}  // namespace nf::metrics
