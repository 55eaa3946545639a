// The fur stage on a small synthetic cat (128 px photos) whose fur starts wrong in a known way: the
// warm start lifts every strand 60 degrees off the skin, where the true fur leaves it at about 32
// degrees and lies down towards the tip. The warm-up and the geometric losses must bring the groom
// far above that baseline groom. The photos are too small to show the fur (a strand spans about
// 1.3 pixels): their image losses pull the groom off the fur (92.9 -> 77.0 at F(2 cm, 20 deg)), so
// the stage weighs them by how many pixels the fur spans (fur_resolution.hpp) and here switches
// them off; the groom must then hold what the warm-up reached, and beat the same run with the image
// losses forced on. Inputs come from the scene's ground truth (bald body, envelope, knowledge), so
// the test measures the optimisation alone, with the default loss weights. The image path itself
// (given strands rendered like the field's, exact resume, the learning-rate ramp) is checked with
// the image losses forced on.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "engine/core/error.hpp"
#include "engine/fur/baseline_groom.hpp"
#include "engine/fur/fur_resolution.hpp"
#include "engine/fur/ground_truth_inputs.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/io/scene.hpp"
#include "engine/io/view_split.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/metrics/groom_scores.hpp"
#include "engine/orient/orientation_scales.hpp"
#include "engine/synth/synth_scene.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::fur;
namespace fs = std::filesystem;

namespace {

double fscore(const metrics::StrandSample& groom, const metrics::StrandSample& truth, double cm, metrics::MatchThreshold t) {
  for (const metrics::MatchScore& s : metrics::match_scores(groom, truth, {t}, cm))
    if (s.directed) return s.fscore;
  return 0;
}

double held_out_iou(FurTrainer& trainer, const FurTrainingData& data) {
  double sum = 0;
  for (const FurView& v : data.held_out) sum += score_view(v, trainer.render(v, trainer.batch(), 5)).silhouette_iou;
  return sum / double(data.held_out.size());
}

}  // namespace

TEST_CASE("fur learning: strands lifted too far come back onto the fur, and photos too small to show it do not pull them off") {
  gpu::Context& ctx = test::context();
  const fs::path dir = fs::temp_directory_path() / "nf_test_fur_learning";
  fs::remove_all(dir);
  synth::SynthOptions so;
  so.animal = "cat", so.views = 10, so.resolution = 128, so.strands = 30000, so.samples_per_axis = 1, so.seed = 4;
  so.body_voxel = 0.008f;  // a coarser body than the default: the test is about the fur
  synth::synthesize_scene(dir / "scene", so);

  GroundTruthInputOptions gi;
  gi.roots = 30000, gi.views.max_side = 128, gi.sdf_resolution = 64;
  const GroundTruthInputs in = ground_truth_inputs(ctx, dir / "scene", gi);
  REQUIRE(in.data.train.size() == 8);
  REQUIRE(in.data.held_out.size() == 2);

  FurTrainingOptions o;
  o.steps = 150, o.strands = 2500, o.warm_steps = 20, o.checkpoint_interval = 0, o.chamfer_queries = 3000;
  o.lying_angle_deg = 60;
  o.length_lr = 0.01f;  // lengths learned after the warm-up (off by default)
  std::unique_ptr<StrandPrior> prior = shipped_strand_prior(ctx);
  FurTrainer trainer(ctx, in.data, *prior, {}, o);
  // The fur spans about 1.3 photo pixels in every view (1.32 measured), below half of the
  // resolved length: no view's image losses run.
  REQUIRE(trainer.view_resolution().size() == in.data.train.size());
  for (const ViewResolution& v : trainer.view_resolution()) {
    CHECK(v.fur_pixels > 0.9);
    CHECK(v.fur_pixels < 1.8);
    CHECK(v.image_weight == 0.0);
  }
  CHECK(image_loss_weight(2.4, 4.8) == 0.0);
  CHECK(image_loss_weight(3.6, 4.8) == doctest::Approx(0.5));
  CHECK(image_loss_weight(4.8, 4.8) == 1.0);
  // Gabor scales: a halving only while the fur spans 2 x 4.8 px in the halved photo.
  CHECK(gabor_scales_for(2.9, 4.8, 3) == 1);   // the demo
  CHECK(gabor_scales_for(10.9, 4.8, 3) == 1);  // a cat at 1024 px
  CHECK(gabor_scales_for(19.2, 4.8, 3) == 2);
  CHECK(gabor_scales_for(35, 4.8, 3) == 2);    // a cat at 2048 px
  CHECK(gabor_scales_for(70, 4.8, 3) == 3);
  CHECK(gabor_scales_for(70, 4.8, 2) == 2);
  CHECK(gabor_scales_for(0, 4.8, 3) == 1);
  CHECK(image_loss_weight(0.1, 0.0) == 1.0);
  CHECK(trainer.warm_state() == nullptr);
  trainer.train(o.warm_steps);
  // The warm-up's field is kept (the stage's selection returns to it): this field, lengths at 1.
  REQUIRE(trainer.warm_state() != nullptr);
  CHECK(trainer.warm_state()->step == o.warm_steps);
  CHECK(trainer.warm_state()->parameters == trainer.field().parameters());
  for (float f : trainer.warm_state()->length_factors) CHECK(f == doctest::Approx(1.0f).epsilon(1e-6));
  // And the 0-step groom (the warm start) it began from.
  CHECK(trainer.start_state().step == 0);
  CHECK(trainer.start_state().parameters != trainer.warm_state()->parameters);
  const double iou_before = held_out_iou(trainer, in.data);
  {
    // Given strands render like the field's: its own strands at the same roots score the same
    // (the warm start's segments are fully confident), and the true groom covers the masks as well
    // as the field's strands at the same count (a wrong frame or scale would leave them empty).
    const std::vector<std::uint32_t> ids = sample_indices(in.data.roots.size(), trainer.batch(), 5);
    std::vector<float> own;
    trainer.field().infer(in.data.roots, ids, 1024, [&](std::size_t, std::uint32_t, const std::vector<float>& p, const std::vector<float>&) {
      own.insert(own.end(), p.begin(), p.end());
    });
    const metrics::StrandSample truth =
        metrics::sample_strands(io::read_hair(io::find_ground_truth(dir / "scene")->strands()), trainer.batch(), kStrandPoints, 3);
    for (const FurView& v : in.data.held_out) {
      const ViewScore field = score_view(v, trainer.render(v, trainer.batch(), 5));
      const ViewScore given = score_view(v, trainer.render_strands(v, own));
      const ViewScore true_groom = score_view(v, trainer.render_strands(v, truth.xyz));
      MESSAGE("held-out view ", v.camera, ": field IoU ", field.silhouette_iou, " orientation ", field.orientation_error_deg,
              " deg; as given strands ", given.silhouette_iou, " / ", given.orientation_error_deg, "; true groom ",
              true_groom.silhouette_iou, " / ", true_groom.orientation_error_deg);
      CHECK(given.silhouette_iou == doctest::Approx(field.silhouette_iou).epsilon(0.01));
      CHECK(given.orientation_error_deg == doctest::Approx(field.orientation_error_deg).epsilon(0.01));
      CHECK(true_groom.silhouette_iou > 0.8 * field.silhouette_iou);
    }
    CHECK_THROWS_AS(trainer.render_strands(in.data.held_out[0], std::vector<float>(7)), InputError);
  }
  // The groom of a trainer and the baseline (the warm start's strands) on the same 3000 roots,
  // against the truth: F(2 cm, 20 deg) and F(3 mm, 30 deg).
  const double cm = in.data.cm_per_unit;
  const std::vector<std::uint32_t> ids = sample_indices(in.data.roots.size(), 3000, 17);
  const metrics::StrandSample truth = metrics::sample_strands(io::read_hair(io::find_ground_truth(dir / "scene")->strands()), 10000, 25, 2);
  const auto scores = [&](FurTrainer& t) {
    std::vector<float> xyz;
    t.field().infer(in.data.roots, ids, 1024, [&](std::size_t, std::uint32_t, const std::vector<float>& p, const std::vector<float>&) {
      xyz.insert(xyz.end(), p.begin(), p.end());
    });
    const metrics::StrandSample groom = metrics::sample_strands(io::StrandSet::uniform(3000, kStrandPoints, xyz), 3000, 25, 1);
    return std::pair{fscore(groom, truth, cm, {2.0, 20.0}), fscore(groom, truth, cm, {0.3, 30.0})};
  };
  const metrics::StrandSample baseline = metrics::sample_strands(baseline_groom(in.data.roots, ids, o.lying_angle_deg), 3000, 25, 1);
  const double f_base = fscore(baseline, truth, cm, {2.0, 20.0}), f_base_mm = fscore(baseline, truth, cm, {0.3, 30.0});
  const auto [f_warm, f_warm_mm] = scores(trainer);

  // Exact resume without image steps: the steps after the warm-up render no view, a checkpoint says
  // so, and a resumed trainer takes the same next step.
  trainer.train(o.warm_steps + 2);
  trainer.save_checkpoint(dir / "gated.nfwt");
  {
    FurTrainer resumed(ctx, in.data, *prior, {}, o);
    REQUIRE(resumed.load_checkpoint(dir / "gated.nfwt"));
    CHECK(resumed.step() == o.warm_steps + 2);
    CHECK_FALSE(resumed.last_report().warm);
    CHECK_FALSE(resumed.last_report().image);
    const FurStepReport a = resumed.train(o.warm_steps + 3);
    const FurStepReport b = trainer.train(o.warm_steps + 3);
    CHECK_FALSE(a.image);
    CHECK_FALSE(b.image);
    CHECK(a.silhouette == 0.0);
    CHECK(a.loss == doctest::Approx(b.loss).epsilon(1e-6));
    CHECK(a.chamfer == doctest::Approx(b.chamfer).epsilon(1e-6));
    // The length factors and the warm-up's field come back with the checkpoint.
    CHECK(resumed.field().length_factors() == trainer.field().length_factors());
    REQUIRE(resumed.warm_state() != nullptr);
    CHECK(resumed.warm_state()->parameters == trainer.warm_state()->parameters);
  }

  const FurStepReport last = trainer.train(o.steps);
  const double iou_after = held_out_iou(trainer, in.data);
  CHECK(trainer.step() == o.steps);
  CHECK(last.skipped_steps == 0);
  CHECK_FALSE(last.warm);
  CHECK_FALSE(last.image);  // no view resolves the fur
  CHECK(last.chamfer > 0);  // the geometric losses of the image phase still run
  const auto [f_groom, f_groom_mm] = scores(trainer);
  // The lengths learned after the warm-up (from the chamfer here) moved, within their bounds.
  double moved = 0;
  for (float f : trainer.field().length_factors()) {
    CHECK(f >= o.length_bounds.lo);
    CHECK(f <= o.length_bounds.hi);
    moved = std::max(moved, std::abs(double(f) - 1.0));
  }
  CHECK(moved > 1e-3);
  {
    // The knowledge here is the truth (factor 1). The chamfer from M_NeuS pulls the lengths out; the
    // envelope loss does not stop a longer strand that lies flatter, so they still grow (1.27; 1.30
    // without the envelope loss), which is why they are off by default. Reported, and bounded.
    double log_sum = 0;
    std::size_t regions = 0;
    std::vector<std::size_t> count(trainer.field().length_factors().size(), 0);
    for (std::int32_t r : in.data.roots.region) ++count[std::size_t(r)];
    for (std::size_t r = 0; r < count.size(); ++r)
      if (count[r]) log_sum += std::log(trainer.field().length_factors()[r]), ++regions;
    const double geometric_mean = std::exp(log_sum / double(std::max<std::size_t>(1, regions)));
    MESSAGE("length factors' geometric mean over the regions with roots: ", geometric_mean);
    CHECK(geometric_mean > 1.0);  // the bias documented above; a fix that ends it should say so here
    CHECK(geometric_mean < o.length_bounds.hi);
  }
  // set_state returns to the warm-up's groom: the same strands as then.
  {
    const FurFieldState trained = trainer.state();
    trainer.set_state(*trainer.warm_state());
    const auto [f_back, f_back_mm] = scores(trainer);
    CHECK(f_back == doctest::Approx(f_warm).epsilon(1e-9));
    CHECK(f_back_mm == doctest::Approx(f_warm_mm).epsilon(1e-9));
    trainer.set_state(trained);
  }

  // The same run with the image losses forced on (every view weighs fully, as before the weighting).
  FurTrainingOptions forced = o;
  forced.resolved_fur_px = 0;
  FurTrainer open(ctx, in.data, *prior, {}, forced);
  for (const ViewResolution& v : open.view_resolution()) CHECK(v.image_weight == 1.0);
  open.train(forced.warm_steps);
  // Exact resume: a trainer loaded from a checkpoint takes the same next step (same roots, view,
  // chamfer points and parameters: the same loss).
  open.save_checkpoint(dir / "checkpoint.nfwt");
  {
    FurTrainer resumed(ctx, in.data, *prior, {}, forced);
    REQUIRE(resumed.load_checkpoint(dir / "checkpoint.nfwt"));
    CHECK(resumed.step() == forced.warm_steps);
    const FurStepReport a = resumed.train(forced.warm_steps + 1);
    const FurStepReport b = open.train(forced.warm_steps + 1);
    CHECK(a.image);
    CHECK(b.image);
    CHECK(a.view == b.view);
    CHECK(a.loss == doctest::Approx(b.loss).epsilon(1e-6));
    CHECK(a.silhouette == doctest::Approx(b.silhouette).epsilon(1e-6));
    CHECK(a.silhouette > 0);
    FurTrainingOptions other = forced;
    other.seed = 2;
    FurTrainer stranger(ctx, in.data, *prior, {}, other);
    CHECK_FALSE(stranger.load_checkpoint(dir / "checkpoint.nfwt"));  // other settings: not resumed
    FurTrainer gated(ctx, in.data, *prior, {}, o);
    CHECK_FALSE(gated.load_checkpoint(dir / "checkpoint.nfwt"));  // nor with another resolved length
  }
  // Native-resolution patches (fur_patches.hpp): the training views' targets at the photos' 128 px
  // in a store, a 48 px window of one a step. The image steps run on patches inside their view,
  // and a resumed trainer takes the same patch and loss.
  {
    const io::Scene scene = io::read_scene(dir / "scene");
    FurPatches store(ctx, in.bald, dir / "patches", 48);
    FurViewOptions vo;
    vo.max_side = 64;  // the views at half the photos' size, the patches at their own
    FurTrainingData patched = in.data;
    patched.train.clear();
    for (std::uint32_t v = 0; v < scene.cameras.size(); ++v) {
      if (io::is_held_out(v, 5)) continue;
      NativeTargets native;
      patched.train.push_back(make_fur_view(ctx, scene, v, nullptr, in.bald, vo, &native));
      CHECK(native.crop.width > 48);  // a window, not the whole view
      CHECK(store.add(v, native) == patched.train.size() - 1);
    }
    patched.patches = &store;
    {
      // The native targets' scales are chosen on the mask's box padded by the filters' reach: the
      // same angles, reliabilities and scales as on the whole photo.
      FurViewOptions three = vo;
      three.gabor_scales = 3;
      three.outline_px = 0;  // no outline band: coarse scales win near the outline too, where they read beyond the box
      NativeTargets native;
      make_fur_view(ctx, scene, 0, nullptr, in.bald, three, &native);
      const io::Camera& cam = scene.cameras[0];
      const io::Image photo = io::read_image(cam.image);
      const std::vector<std::uint8_t> mask = io::mask_of(io::read_image(cam.mask));
      const orient::OrientationOf gabor = [&](const io::Image& i, const std::vector<std::uint8_t>& m) { return orient::gabor_orientation(ctx, i, &m); };
      const orient::ScaledOrientation whole = orient::scaled_orientation(photo, mask, 3, three.coherence_px, gabor, 0);
      const auto x0 = std::uint32_t(std::lround(cam.cx - native.crop.cx)), y0 = std::uint32_t(std::lround(cam.cy - native.crop.cy));
      std::size_t coarse = 0;
      for (std::uint32_t y = 0; y < native.crop.height; ++y)
        for (std::uint32_t x = 0; x < native.crop.width; ++x) {
          const std::size_t at = std::size_t(y) * native.crop.width + x, i = std::size_t(y + y0) * cam.width + x + x0;
          REQUIRE(native.scale[at] == whole.scale[i]);
          REQUIRE(native.angle[at] == doctest::Approx(whole.angle[i]).epsilon(1e-6));
          REQUIRE(native.confidence[at] == doctest::Approx(whole.reliability[i]).epsilon(1e-6));
          coarse += native.scale[at] > 0;
        }
      CHECK(coarse > 0);  // the comparison covers the coarse scales
    }
    FurTrainer p(ctx, patched, *prior, {}, forced);
    p.train(forced.warm_steps + 2);
    const FurStepReport r = p.last_report();
    CHECK(r.image);
    CHECK(std::isfinite(r.loss));
    CHECK(r.silhouette > 0);
    CHECK(r.pass_seconds.contains("patch"));
    p.save_checkpoint(dir / "patched.nfwt");
    FurTrainer q(ctx, patched, *prior, {}, forced);
    REQUIRE(q.load_checkpoint(dir / "patched.nfwt"));
    const FurStepReport a = q.train(forced.warm_steps + 3), b = p.train(forced.warm_steps + 3);
    CHECK(a.view == b.view);
    CHECK(a.loss == doctest::Approx(b.loss).epsilon(1e-6));
  }
  CHECK_FALSE(fs::exists(dir / "patches"));  // the store's files go with it

  open.train(forced.steps);
  const auto [f_open, f_open_mm] = scores(open);

  char line[300];
  std::snprintf(line, sizeof line,
                "F(2 cm, 20 deg) / F(3 mm, 30 deg): baseline %.1f / %.1f, warm-up %.1f / %.1f, end %.1f / %.1f, end with the image "
                "losses forced on %.1f / %.1f; held-out silhouette IoU %.3f -> %.3f",
                f_base, f_base_mm, f_warm, f_warm_mm, f_groom, f_groom_mm, f_open, f_open_mm, iou_before, iou_after);
  MESSAGE(line);
  // Measured: baseline 39.3 / 6.9, warm-up 92.9 / 45.5, end 94.1 / 43.7 (93.7 / 39.7 without the
  // envelope loss), forced on 70.8 / 19.6 (the margins leave room for float-atomic and device
  // noise). The end's loss at 3 mm against the warm-up is the chamfer's and the curvature's, which
  // start with the image phase.
  CHECK(f_groom >= f_base + 15.0);
  CHECK(f_groom_mm >= f_base_mm + 5.0);
  CHECK(f_groom >= f_warm - 2.0);
  CHECK(f_groom >= f_open + 8.0);
  CHECK(f_groom_mm >= f_open_mm + 8.0);
  CHECK(iou_after >= iou_before - 0.02);

  // The image losses' learning-rate ramp: the warm steps and the steps after the ramp follow the
  // cosine schedule, the ramp's steps a linear share of it.
  FurTrainingOptions ramped = forced;
  ramped.steps = 8, ramped.strands = 300, ramped.warm_steps = 2, ramped.image_ramp_steps = 4, ramped.chamfer_queries = 300;
  FurTrainer ramp_trainer(ctx, in.data, *prior, {}, ramped);
  const nn::LearningRateSchedule cosine{ramped.lr, 0, ramped.steps, ramped.lr_floor};
  const float shares[8] = {1, 1, 0.25f, 0.5f, 0.75f, 1, 1, 1};
  for (std::uint32_t step = 0; step < ramped.steps; ++step) {
    const FurStepReport r = ramp_trainer.train(step + 1);
    const float share = shares[step];
    CHECK(r.warm == (step < ramped.warm_steps));
    CHECK(r.lr == doctest::Approx(cosine.at(step) * share).epsilon(1e-6));
  }
  fs::remove_all(dir);
}
