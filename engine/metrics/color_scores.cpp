#include "engine/metrics/color_scores.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/color.hpp"
#include "engine/core/error.hpp"
#include "engine/geometry/point_index.hpp"

namespace nf::metrics {
namespace {

// Linear interpolation at t in [0, 1] between `n` colours spread evenly from root to tip.
glm::vec3 along(const float* rgb, std::uint32_t n, float t) {
  const float x = std::clamp(t, 0.f, 1.f) * float(n - 1);
  const std::uint32_t k0 = std::min(std::uint32_t(x), n - 1), k1 = std::min(k0 + 1, n - 1);
  const float f = x - float(k0);
  const float* a = rgb + 3 * k0;
  const float* b = rgb + 3 * k1;
  return {a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])};
}

json summary(std::vector<double> v) {
  if (v.empty()) return {{"count", 0}};
  std::sort(v.begin(), v.end());
  double sum = 0;
  for (double x : v) sum += x;
  return {{"count", v.size()}, {"mean", sum / double(v.size())}, {"median", v[v.size() / 2]}, {"p90", v[std::min(v.size() - 1, v.size() * 9 / 10)]}};
}

}  // namespace

glm::vec3 ColorTruth::at(std::size_t strand, float t) const { return along(&rgb[strand * samples * 3], samples, t); }

ColorTruth color_truth(const io::StrandSet& truth, std::uint32_t samples) {
  if (truth.colors.empty()) throw InputError("the true strands carry no colours (a synth scene older than its colour array)");
  NF_CHECK(samples >= 2, "colour truth: at least root and tip");
  ColorTruth c;
  c.samples = samples;
  c.roots.reserve(3 * std::size_t(truth.strand_count()));
  c.rgb.reserve(3 * std::size_t(truth.strand_count()) * samples);
  for (std::uint32_t s = 0; s < truth.strand_count(); ++s) {
    const std::size_t first = truth.offsets[s];
    c.roots.insert(c.roots.end(), &truth.points[3 * first], &truth.points[3 * first] + 3);
    for (std::uint32_t k = 0; k < samples; ++k) {
      const glm::vec3 v = along(&truth.colors[3 * first], truth.points_in(s), float(k) / float(samples - 1));
      c.rgb.insert(c.rgb.end(), {v.r, v.g, v.b});
    }
  }
  return c;
}

json color_scores(const GroomColors& g, const ColorTruth& truth, std::uint32_t max_strands) {
  const std::uint64_t n = g.roots.size() / 3;
  NF_CHECK(g.seen.size() == n && g.controls > 0 && truth.strands() > 0, "colour scores: per-strand arrays do not match");
  const geometry::PointIndex index(truth.roots);
  const std::uint64_t cap = std::max<std::uint32_t>(1, max_strands), every = std::max<std::uint64_t>(1, (n + cap - 1) / cap);
  struct Pair {
    glm::vec3 estimate, truth, local;  // local: the mean of the kLocal nearest true strands' colours
    bool seen;
    std::uint32_t control;
  };
  constexpr std::size_t kLocal = 8;
  std::vector<Pair> pairs;
  for (std::uint64_t s = 0; s < n; s += every) {
    const std::vector<std::uint32_t> near = index.nearest_k(&g.roots[3 * s], kLocal);
    for (std::uint32_t c = 1; c <= g.controls; ++c) {
      const float t = float(c) / float(g.controls);
      glm::vec3 local(0);
      for (std::uint32_t k : near) local += truth.at(k, t);
      pairs.push_back({g.at(s, t), truth.at(near[0], t), local / float(near.size()), g.seen[s] != 0, c - 1});
    }
  }
  // The exposure: the gain on the estimate's luminance that best fits the truth's (seen strands).
  double num = 0, den = 0;
  for (const Pair& p : pairs)
    if (p.seen) num += double(color::luminance(p.estimate)) * color::luminance(p.truth), den += double(color::luminance(p.estimate)) * color::luminance(p.estimate);
  const double gain = den > 0 ? num / den : 1.0;
  std::vector<double> seen, unseen, seen_local, seen_lightness, seen_chroma;
  std::vector<double> by_control(g.controls, 0.0), count(g.controls, 0.0);
  for (const Pair& p : pairs) {
    const double e = color::delta_e(p.estimate * float(gain), p.truth);
    (p.seen ? seen : unseen).push_back(e);
    if (!p.seen) continue;
    by_control[p.control] += e, count[p.control] += 1, seen_local.push_back(color::delta_e(p.estimate * float(gain), p.local));
    // What the error is made of: lightness (shading, the light's colour left out) or hue and saturation.
    const glm::vec3 d = color::lab_of_linear(p.estimate * float(gain)) - color::lab_of_linear(p.truth);
    seen_lightness.push_back(std::abs(d.x)), seen_chroma.push_back(std::hypot(d.y, d.z));
  }
  json along = json::array();  // seen strands' mean at t = 1/C .. 1: how far the colour along a strand is off
  for (std::uint32_t c = 0; c < g.controls; ++c) along.push_back(count[c] > 0 ? by_control[c] / count[c] : 0.0);
  return {{"delta_e_seen", summary(seen)}, {"delta_e_unseen", summary(unseen)}, {"delta_e_seen_along", along},
          {"delta_e_seen_local", summary(seen_local)}, {"delta_l_seen", summary(seen_lightness)},
          {"delta_ab_seen", summary(seen_chroma)}, {"exposure_gain", gain},
          {"strands_scored", (n + every - 1) / every}};
}

}  // namespace nf::metrics
