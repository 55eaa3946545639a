#include "engine/metrics/strand_metrics.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <future>
#include <numeric>
#include <random>

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/feature_index.hpp"
#include "engine/geometry/point_index.hpp"

namespace nf::metrics {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct V3 {
  double x, y, z;
};
V3 at(const std::vector<float>& xyz, std::size_t i) { return {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]}; }
V3 sub(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
double norm(V3 a) { return std::sqrt(dot(a, a)); }
V3 unit(V3 a) {
  const double n = norm(a);
  return n > 0 ? V3{a.x / n, a.y / n, a.z / n} : V3{0, 0, 0};
}

// Unit direction of the segment at each point (the last point takes its incoming segment).
std::vector<float> point_directions(const StrandSample& s) {
  std::vector<float> dirs(s.xyz.size());
  for (std::uint32_t i = 0; i < s.strands; ++i)
    for (std::uint32_t l = 0; l < s.points; ++l) {
      const std::size_t p = std::size_t(i) * s.points + l;
      const std::size_t a = l + 1 < s.points ? p : p - 1;
      const V3 d = s.points > 1 ? unit(sub(at(s.xyz, a + 1), at(s.xyz, a))) : V3{0, 0, 0};
      dirs[3 * p] = float(d.x), dirs[3 * p + 1] = float(d.y), dirs[3 * p + 2] = float(d.z);
    }
  return dirs;
}

// Per threshold: how many points of `from` have a point of `to` within the distance whose segment
// direction is within the angle (directed and undirected), as the reference evaluation does (a
// ball query: any point in it may match). Candidates come from a ball in (position, w direction)
// space with w = d / sqrt(2 - 2 cos angle): every match lies within sqrt(2) d there, while points
// pointing elsewhere do not, so even a prediction with no matches is cheap to score. Candidates
// are then checked exactly; a query stops at its first match.
void count_matches(const StrandSample& from, const std::vector<float>& from_dirs, const StrandSample& to,
                   const std::vector<float>& to_dirs, const std::vector<MatchThreshold>& thresholds, double cm_per_unit,
                   std::vector<std::uint64_t>& directed, std::vector<std::uint64_t>& undirected) {
  const std::size_t nt = thresholds.size();
  directed.assign(nt, 0);
  undirected.assign(nt, 0);
  if (from.xyz.empty() || to.xyz.empty()) return;
  const std::size_t n_from = from.xyz.size() / 3, n_to = to.xyz.size() / 3;
  // One tree for all thresholds: w from the first; each threshold gets the radius that keeps its
  // matches inside, sqrt(d^2 + w^2 (2 - 2 cos angle)).
  std::vector<double> dist(nt), cos_angle(nt);
  std::vector<float> radius(nt);
  for (std::size_t t = 0; t < nt; ++t)
    dist[t] = thresholds[t].distance_cm / cm_per_unit, cos_angle[t] = std::cos(thresholds[t].angle_deg * kPi / 180.0);
  const float w = float(dist[0] / std::sqrt(std::max(2.0 - 2.0 * cos_angle[0], 1e-12)));
  for (std::size_t t = 0; t < nt; ++t)
    radius[t] = float(std::sqrt(dist[t] * dist[t] + double(w) * w * (2.0 - 2.0 * cos_angle[t]))) * 1.0001f;
  std::vector<float> features(n_to * 6);
  for (std::size_t q = 0; q < n_to; ++q)
    for (int c = 0; c < 3; ++c) features[6 * q + c] = to.xyz[3 * q + c], features[6 * q + 3 + c] = w * to_dirs[3 * q + c];
  const geometry::FeatureIndex index(features, 6);
  std::vector<std::atomic<std::uint64_t>> hits_d(nt), hits_u(nt);
  parallel_for(n_from, [&](std::size_t begin, std::size_t end) {
    std::vector<std::uint64_t> local_d(nt, 0), local_u(nt, 0);
    for (std::size_t p = begin; p < end; ++p) {
      const float* x = &from.xyz[3 * p];
      const float* u = &from_dirs[3 * p];
      // sign +1: the directed match; -1: the reversed direction, which the undirected score accepts.
      auto search = [&](std::size_t t, float sign) {
        const float query[6] = {x[0], x[1], x[2], sign * w * u[0], sign * w * u[1], sign * w * u[2]};
        bool found = false;
        index.visit_within(query, radius[t], [&](std::uint32_t q, float) {
          const double dx = double(x[0]) - to.xyz[3 * q], dy = double(x[1]) - to.xyz[3 * q + 1], dz = double(x[2]) - to.xyz[3 * q + 2];
          const double c = sign * (double(u[0]) * to_dirs[3 * q] + double(u[1]) * to_dirs[3 * q + 1] + double(u[2]) * to_dirs[3 * q + 2]);
          found = dx * dx + dy * dy + dz * dz <= dist[t] * dist[t] && c > cos_angle[t];
          return !found;
        });
        return found;
      };
      for (std::size_t t = 0; t < nt; ++t) {
        const bool match_d = search(t, 1.0f);
        local_d[t] += match_d;
        local_u[t] += match_d || search(t, -1.0f);
      }
    }
    for (std::size_t t = 0; t < nt; ++t) hits_d[t] += local_d[t], hits_u[t] += local_u[t];
  });
  for (std::size_t t = 0; t < nt; ++t) directed[t] = hits_d[t], undirected[t] = hits_u[t];
}

}  // namespace

StrandSample sample_strands(const io::StrandSet& set, std::uint32_t max_strands, std::uint32_t points, unsigned seed) {
  if (points < 2) throw InputError("metrics: strands need at least 2 sample points");
  std::vector<std::uint32_t> chosen(set.strand_count());
  std::iota(chosen.begin(), chosen.end(), 0u);
  if (chosen.size() > max_strands) {
    std::mt19937 rng(seed);
    for (std::uint32_t i = 0; i < max_strands; ++i)
      std::swap(chosen[i], chosen[i + std::uniform_int_distribution<std::size_t>(0, chosen.size() - 1 - i)(rng)]);
    chosen.resize(max_strands);
    std::sort(chosen.begin(), chosen.end());  // the same subset gives the same sample, in file order
  }
  StrandSample s;
  s.points = points;
  for (std::uint32_t strand : chosen) {
    const std::uint32_t first = set.offsets[strand], n = set.points_in(strand);
    if (n < 2) continue;  // a lone point has no direction: nothing to compare
    std::vector<double> arc(n, 0.0);
    for (std::uint32_t p = 1; p < n; ++p) arc[p] = arc[p - 1] + norm(sub(at(set.points, first + p), at(set.points, first + p - 1)));
    if (!(arc.back() > 0)) continue;  // zero length: no direction either
    for (std::uint32_t k = 0; k < points; ++k) {
      const double target = arc.back() * k / (points - 1);
      std::uint32_t p = std::uint32_t(std::upper_bound(arc.begin(), arc.end(), target) - arc.begin());
      p = std::clamp<std::uint32_t>(p, 1, std::max(1u, n - 1));
      V3 v = at(set.points, first + p - 1);
      if (n > 1) {
        const double span = arc[p] - arc[p - 1];
        const double t = span > 0 ? std::clamp((target - arc[p - 1]) / span, 0.0, 1.0) : 0.0;
        const V3 b = at(set.points, first + p);
        v = {v.x + t * (b.x - v.x), v.y + t * (b.y - v.y), v.z + t * (b.z - v.z)};
      }
      s.xyz.insert(s.xyz.end(), {float(v.x), float(v.y), float(v.z)});
    }
    ++s.strands;
  }
  return s;
}

std::vector<MatchThreshold> default_thresholds() { return {{2, 20}, {3, 30}, {4, 40}}; }

std::vector<MatchScore> match_scores(const StrandSample& predicted, const StrandSample& truth,
                                     const std::vector<MatchThreshold>& thresholds, double cm_per_unit) {
  if (!(cm_per_unit > 0)) throw InputError("metrics: the scene scale (cm per unit) must be positive");
  const auto pred_dirs = point_directions(predicted), true_dirs = point_directions(truth);
  std::vector<std::uint64_t> p_d, p_u, r_d, r_u;
  // Precision and recall each build a tree (single-threaded in nanoflann): run them side by side.
  auto recall_counts = std::async(std::launch::async, [&] { count_matches(truth, true_dirs, predicted, pred_dirs, thresholds, cm_per_unit, r_d, r_u); });
  count_matches(predicted, pred_dirs, truth, true_dirs, thresholds, cm_per_unit, p_d, p_u);
  recall_counts.get();
  const double n_pred = double(predicted.xyz.size() / 3), n_true = double(truth.xyz.size() / 3);
  std::vector<MatchScore> scores;
  for (std::size_t t = 0; t < thresholds.size(); ++t)
    for (bool directed : {true, false}) {
      const double precision = n_pred ? 100.0 * double(directed ? p_d[t] : p_u[t]) / n_pred : 0.0;
      const double recall = n_true ? 100.0 * double(directed ? r_d[t] : r_u[t]) / n_true : 0.0;
      const double f = precision + recall > 0 ? 2 * precision * recall / (precision + recall) : 0.0;
      scores.push_back({thresholds[t], directed, precision, recall, f});
    }
  return scores;
}

ConsistencyMetrics consistency_metrics(const StrandSample& s, double cm_per_unit, std::uint32_t neighbours) {
  if (!(cm_per_unit > 0)) throw InputError("metrics: the scene scale (cm per unit) must be positive");
  ConsistencyMetrics m;
  const std::uint32_t N = s.strands, M = s.points;
  if (N == 0) return m;
  if (M < 3) throw InputError("metrics: consistency needs at least 3 points per strand (bending angles)");
  std::vector<double> length(N, 0.0), theta(std::size_t(N) * (M - 2), 0.0);
  std::vector<V3> mean_dir(N), first_dir(N);
  std::vector<float> roots(std::size_t(N) * 3);
  for (std::uint32_t i = 0; i < N; ++i) {
    const std::size_t base = std::size_t(i) * M;
    V3 sum{0, 0, 0}, previous{0, 0, 0};
    for (std::uint32_t l = 0; l + 1 < M; ++l) {
      const V3 d = sub(at(s.xyz, base + l + 1), at(s.xyz, base + l));
      length[i] += norm(d);
      const V3 b = unit(d);
      sum = {sum.x + b.x, sum.y + b.y, sum.z + b.z};
      if (l == 0) first_dir[i] = b;
      else theta[std::size_t(i) * (M - 2) + l - 1] = std::acos(std::clamp(dot(previous, b), -1.0, 1.0));
      previous = b;
    }
    mean_dir[i] = unit(sum);
    for (int a = 0; a < 3; ++a) roots[3 * i + a] = s.xyz[3 * base + a];
  }
  // Global length statistics and curvature.
  const double mean_length = std::accumulate(length.begin(), length.end(), 0.0) / N;
  double var_length = 0;
  for (double L : length) var_length += (L - mean_length) * (L - mean_length);
  m.length_mean_cm = mean_length * cm_per_unit;
  m.length_std_cm = std::sqrt(var_length / N) * cm_per_unit;
  if (M > 2) {
    std::vector<double> mean_theta(M - 2, 0.0);
    for (std::uint32_t i = 0; i < N; ++i)
      for (std::uint32_t l = 0; l < M - 2; ++l) mean_theta[l] += theta[std::size_t(i) * (M - 2) + l] / N;
    double shape = 0, most = 0;
    for (std::uint32_t i = 0; i < N; ++i) {
      double d2 = 0;
      for (std::uint32_t l = 0; l < M - 2; ++l) {
        const double t = theta[std::size_t(i) * (M - 2) + l];
        d2 += (t - mean_theta[l]) * (t - mean_theta[l]);
        most = std::max(most, t);
      }
      shape += std::sqrt(d2) / (M - 2);
    }
    m.curvature_var_global = shape / N;
    m.max_bending_deg = most * 180.0 / kPi;
  }
  // Local terms over each strand's nearest roots.
  if (N > 1) {
    const geometry::PointIndex index(roots);
    const std::uint32_t k = std::min(neighbours, N - 1);
    std::vector<double> local_length(N), local_curv(N), local_dir(N), local_first(N);
    parallel_for(N, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        std::vector<std::uint32_t> near = index.nearest_k(&roots[3 * i], k + 1);
        near.erase(std::remove(near.begin(), near.end(), std::uint32_t(i)), near.end());
        near.resize(std::min<std::size_t>(near.size(), k));
        double ll = 0, lc = 0, ld = 0, lf = 0;
        for (std::uint32_t j : near) {
          ll += (length[i] - length[j]) * (length[i] - length[j]);
          if (M > 2) {
            double c = 0;
            for (std::uint32_t l = 0; l < M - 2; ++l) {
              const double diff = theta[i * (M - 2) + l] - theta[std::size_t(j) * (M - 2) + l];
              c += diff * diff;
            }
            lc += c / (M - 2);
          }
          const V3 dt = sub(mean_dir[i], mean_dir[j]), df = sub(first_dir[i], first_dir[j]);
          ld += dot(dt, dt);
          lf += dot(df, df);
        }
        const double count = std::max<std::size_t>(1, near.size());
        local_length[i] = ll / count, local_curv[i] = lc / count, local_dir[i] = ld / count, local_first[i] = lf / count;
      }
    });
    const auto mean = [&](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / N; };
    m.local_length_std_cm = std::sqrt(mean(local_length)) * cm_per_unit;
    m.curvature_var_local = mean(local_curv);
    m.direction_var_local = mean(local_dir);
    m.first_direction_var_local = mean(local_first);
  }
  return m;
}

json to_json(const std::vector<MatchScore>& scores) {
  json out = json::array();
  for (const MatchScore& s : scores)
    out.push_back({{"distance_cm", s.threshold.distance_cm}, {"angle_deg", s.threshold.angle_deg},
                   {"directed", s.directed}, {"precision", s.precision}, {"recall", s.recall}, {"fscore", s.fscore}});
  return out;
}

json to_json(const ConsistencyMetrics& m) {
  return {{"length_mean_cm", m.length_mean_cm},
          {"length_std_cm", m.length_std_cm},
          {"local_length_std_cm", m.local_length_std_cm},
          {"curvature_var_global", m.curvature_var_global},
          {"curvature_var_local", m.curvature_var_local},
          {"max_bending_deg", m.max_bending_deg},
          {"direction_var_local", m.direction_var_local},
          {"first_direction_var_local", m.first_direction_var_local}};
}

}  // namespace nf::metrics
