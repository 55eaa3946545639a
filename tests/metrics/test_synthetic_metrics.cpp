// The metrics on a synthetic animal's ground truth: against itself they are perfect, against
// perturbed copies they fall in the expected order, reversed strands fail only the directed score,
// the unsupervised length statistics match what the fur was grown with, and the strand tips and
// the body sit where the fur envelope says.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "engine/body/quadruped.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/metrics/strand_metrics.hpp"
#include "engine/metrics/surface_metrics.hpp"
#include "engine/synth/fur_envelope.hpp"
#include "engine/synth/fur_growth.hpp"

using namespace nf;

namespace {

constexpr double kCmPerUnit = 100.0;  // synthetic scenes are in metres

struct Animal {
  geometry::Mesh body;
  knowledge::Knowledge knowledge;
  synth::Fur fur;
};

const Animal& fox() {
  static const Animal a = [] {
    Animal out;
    const auto p = body::animal_proportions("fox");
    out.body = body::pose_body(body::build_quadruped(p, {p.torso_length / 70}), {});
    out.knowledge = knowledge::preset("fox");
    synth::GrowOptions o;
    o.strand_count = 20000, o.points_per_strand = 100, o.seed = 11, o.animal = "fox", o.torso_length = p.torso_length;
    out.fur = synth::grow_fur(out.body, out.knowledge, synth::fur_style("fox"), o);
    return out;
  }();
  return a;
}

// 8,000 strands of 50 points: enough for stable percentages, fast enough for every CI run.
metrics::StrandSample sample(const io::StrandSet& s, unsigned seed = 1) { return metrics::sample_strands(s, 8000, 50, seed); }

// Every point of every strand moved by gaussian noise of `sigma_cm` (per strand: a rigid shift).
io::StrandSet shifted(const io::StrandSet& s, double sigma_cm, unsigned seed) {
  io::StrandSet out = s;
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, float(sigma_cm / kCmPerUnit));
  for (std::uint32_t k = 0; k < s.strand_count(); ++k) {
    const float d[3] = {g(rng), g(rng), g(rng)};
    for (std::uint32_t i = s.offsets[k]; i < s.offsets[k + 1]; ++i)
      for (int c = 0; c < 3; ++c) out.points[3 * i + c] += d[c];
  }
  return out;
}

double fscore(const std::vector<metrics::MatchScore>& scores, double distance_cm, bool directed) {
  for (const auto& m : scores)
    if (m.threshold.distance_cm == distance_cm && m.directed == directed) return m.fscore;
  FAIL("no score at " << distance_cm << " cm");
  return 0;
}

}  // namespace

TEST_CASE("ground truth against itself scores 100 and against perturbed copies less, in order") {
  const Animal& a = fox();
  const auto truth = sample(a.fur.strands);
  const auto thresholds = metrics::default_thresholds();
  for (const auto& m : metrics::match_scores(truth, truth, thresholds, kCmPerUnit)) {
    CHECK(m.precision == doctest::Approx(100));
    CHECK(m.recall == doctest::Approx(100));
    CHECK(m.fscore == doctest::Approx(100));
  }
  // Independent re-sampling of the same strands (different subset of the same coat) stays high.
  const auto small = metrics::match_scores(sample(shifted(a.fur.strands, 0.3, 1)), truth, thresholds, kCmPerUnit);
  const auto large = metrics::match_scores(sample(shifted(a.fur.strands, 3.0, 2)), truth, thresholds, kCmPerUnit);
  for (bool directed : {true, false}) {
    CAPTURE(directed);
    CHECK(fscore(small, 2, directed) > 90);
    CHECK(fscore(large, 2, directed) < fscore(small, 2, directed) - 20);
    // A looser threshold never scores lower.
    CHECK(fscore(large, 3, directed) >= fscore(large, 2, directed));
    CHECK(fscore(large, 4, directed) >= fscore(large, 3, directed));
  }
  // Strands reversed (tip first): the directed score collapses, the undirected one does not move.
  io::StrandSet reversed = a.fur.strands;
  for (std::uint32_t k = 0; k < reversed.strand_count(); ++k)
    for (std::uint32_t i = reversed.offsets[k], j = reversed.offsets[k + 1] - 1; i < j; ++i, --j)
      for (int c = 0; c < 3; ++c) std::swap(reversed.points[3 * i + c], reversed.points[3 * j + c]);
  const auto flipped = metrics::match_scores(sample(reversed), truth, thresholds, kCmPerUnit);
  CHECK(fscore(flipped, 2, true) < 5);
  CHECK(fscore(flipped, 2, false) == doctest::Approx(100));
}

TEST_CASE("unsupervised metrics of the ground truth match what it was grown with") {
  const Animal& a = fox();
  const auto s = sample(a.fur.strands);
  const auto c = metrics::consistency_metrics(s, kCmPerUnit);
  // The expected mean length: the knowledge's length of each strand's region (the 12 % jitter
  // averages out over 8,000 strands).
  const auto c_all = metrics::consistency_metrics(metrics::sample_strands(a.fur.strands, 20000, 50, 1), kCmPerUnit);
  double expected = 0;
  for (std::uint16_t r : a.fur.strands.regions) expected += a.knowledge.at(static_cast<body::Region>(r)).length_cm;
  expected /= a.fur.strands.strand_count();
  CHECK(c_all.length_mean_cm == doctest::Approx(expected).epsilon(0.01));
  CHECK(c.length_mean_cm == doctest::Approx(expected).epsilon(0.02));
  CHECK(c.length_std_cm > 0);
  CHECK(c.local_length_std_cm < c.length_std_cm);  // neighbours share a region, so a length
  CHECK(c.max_bending_deg < 120);
}

TEST_CASE("the fur envelope holds the strand tips and stands a fur thickness above the body") {
  const Animal& a = fox();
  const synth::Envelope env = synth::fur_envelope(a.body, a.fur.strands);
  const auto tips = metrics::tip_chamfer(sample(a.fur.strands), env.mesh, kCmPerUnit, 50000);
  // Tips lie on the envelope up to the closing radius (the closing rounds the fringe).
  CHECK(tips.tips_to_surface_mm < 10 * env.closing_radius * kCmPerUnit);
  const auto surface = metrics::surface_metrics(env.mesh, a.body, kCmPerUnit, 5.0, 50000);
  // The fox's fur is 0.6-7.8 cm long and lies down: the envelope is a few mm to a few cm out.
  CHECK(surface.chamfer_mean_mm > 2.0);
  CHECK(surface.chamfer_mean_mm < 40.0);
  const auto self = metrics::surface_metrics(env.mesh, env.mesh, kCmPerUnit, 5.0, 50000);
  CHECK(self.chamfer_mean_mm < 0.5);
  CHECK(self.normal_consistency > 0.99);
}
