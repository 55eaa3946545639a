// The fur stage's choice between the warm-up's groom and the trained one (fur_selection.hpp): the
// trained groom is kept only when it loses on no signal beyond its tolerance and gains on one.
#include <doctest/doctest.h>

#include "engine/pipeline/fur_selection.hpp"

using namespace nf::pipeline;

namespace {
GroomSignals signals(double iou, double orientation, double tips, double envelope, bool held_out = true) {
  GroomSignals g;
  g.held_out = held_out, g.silhouette_iou = iou, g.orientation_error_deg = orientation;
  g.tips_to_envelope_mm = tips, g.envelope_to_tips_mm = envelope;
  return g;
}
}  // namespace

TEST_CASE("fur selection: the trained groom is kept only where the held-out views and M_NeuS say it helped") {
  const GroomSignals warm = signals(0.80, 40.0, 4.0, 6.0);  // envelope chamfer 5 mm
  SUBCASE("better everywhere: trained") {
    const GroomChoice c = choose_groom(warm, signals(0.85, 38.0, 3.5, 5.5));
    CHECK(c.trained);
    CHECK(c.reason.find("held-out IoU 0.850") != std::string::npos);
  }
  SUBCASE("orientation better but the tips left M_NeuS (the case the held-out orientation alone misses): warm") {
    const GroomChoice c = choose_groom(warm, signals(0.80, 37.0, 7.0, 6.0));
    CHECK_FALSE(c.trained);
    CHECK(c.reason.find("off M_NeuS") != std::string::npos);
  }
  SUBCASE("a larger share gained on the held-out orientation than lost at M_NeuS (a wrong direction corrected): trained") {
    const GroomChoice c = choose_groom(warm, signals(0.795, 30.0, 4.5, 7.3));  // orientation 25 % better, chamfer 18 % worse
    CHECK(c.trained);
    CHECK(c.reason.find("outweighs") != std::string::npos);
    CHECK_FALSE(choose_groom(warm, signals(0.795, 36.0, 4.5, 7.3)).trained);  // 10 % better against 18 % worse
    CHECK_FALSE(choose_groom(warm, signals(0.795, 30.0, 4.5, 7.3, false)).trained);  // no held-out view to weigh it
  }
  SUBCASE("the silhouette got worse: warm") {
    const GroomChoice c = choose_groom(warm, signals(0.78, 36.0, 3.0, 5.0));
    CHECK_FALSE(c.trained);
    CHECK(c.reason.find("silhouette") != std::string::npos);
  }
  SUBCASE("the orientation got worse: warm") {
    CHECK_FALSE(choose_groom(warm, signals(0.86, 41.0, 3.0, 5.0)).trained);
  }
  SUBCASE("within every tolerance but better on none: warm") {
    const GroomChoice c = choose_groom(warm, signals(0.805, 39.9, 4.05, 6.05));
    CHECK_FALSE(c.trained);
    CHECK(c.reason.find("gained on no signal") != std::string::npos);
  }
  SUBCASE("a loss inside the tolerance with a gain elsewhere: trained") {
    CHECK(choose_groom(warm, signals(0.795, 38.0, 4.1, 6.1)).trained);
  }
  SUBCASE("without held-out views only M_NeuS decides") {
    const GroomSignals w = signals(0, 0, 4.0, 6.0, false);
    CHECK(choose_groom(w, signals(0, 0, 3.0, 5.0, false)).trained);
    CHECK_FALSE(choose_groom(w, signals(0, 0, 4.0, 6.0, false)).trained);
    CHECK(choose_groom(w, signals(0, 0, 3.0, 5.0, false)).reason.find("no held-out view") != std::string::npos);
  }
  SUBCASE("tolerances are the caller's") {
    GroomChoiceTolerances strict;
    strict.iou = 0, strict.envelope = 0, strict.orientation_deg = 0;
    CHECK_FALSE(choose_groom(warm, signals(0.795, 38.0, 4.1, 6.1), strict).trained);
  }
}

TEST_CASE("fur selection: the signals' record") {
  const nf::json j = to_json(signals(0.8, 40.0, 4.0, 6.0));
  CHECK(j["envelope_mm"].get<double>() == doctest::Approx(5.0));
  CHECK(j["held_out"]["silhouette_iou"].get<double>() == doctest::Approx(0.8));
  CHECK_FALSE(to_json(signals(0, 0, 1, 1, false)).contains("held_out"));
}
