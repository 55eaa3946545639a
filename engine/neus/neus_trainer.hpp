#pragma once
// Training of the NeuS field (the surface stage's optimisation loop): per step, rays only where
// the masks say they matter (ray_sampling.hpp), coarse samples spread over the occupied cells of
// each ray (the visual hull, later pruned of the SDF's deep interior) and fine samples placed by
// NeuS up-sampling near the current surface, the field's forward, NeuS volume
// rendering, colour L1 + mask BCE + Eikonal, the adjoints, and Adam (warm-up then cosine; no weight
// decay) on the hash table and both MLPs; the inverse variance exp(10 v) is learned on the host.
// Checkpoints hold everything a resumed run needs (parameters, optimiser moments, occupancy, step,
// the loss curve), so a killed run continues where it stopped. Rays and samples are a function of
// (seed, step, the current field); runs differ only through the summation order of float atomics
// (hash-grid adjoint, inverse-variance gradient).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/io/scene.hpp"
#include "engine/neus/neus_field.hpp"
#include "engine/neus/ray_sampling.hpp"
#include "engine/neus/render_loss.hpp"
#include "engine/neus/visual_hull.hpp"
#include "engine/neus/volume_render.hpp"
#include "engine/nn/adam.hpp"
#include "engine/nn/weights_io.hpp"

namespace nf::neus {

struct NeusTrainingOptions {
  std::uint32_t steps = 2000;
  std::uint32_t rays = 1024;            // per step
  std::uint32_t samples_per_ray = 32;
  std::uint32_t fine_samples = 16;      // of samples_per_ray: placed by NeuS up-sampling (0: all stratified)
  float lr = 1e-2f;                     // hash table and MLPs (instant-nsr-pl's rate)
  float variance_lr = 1e-3f;
  std::uint32_t warmup = 100;
  float lr_floor = 0.1f;                // cosine decay to this share of lr at the last step
  // Mask BCE at 1, not NeuS's 0.1: on furry silhouettes the colour term alone pulls the surface
  // outwards (measured on the synthetic cat: 2.9 % of the diagonal at 0.1, 0.39 % at 1).
  RenderLossWeights weights{1.f, 1.f};
  float eikonal = 0.1f;
  float init_variance = 0.3f;           // inv_s = exp(10 v) starts at e^3
  // inv_s >= sharpness / h (h: the finite-difference step, which follows the hash grid's
  // coarse-to-fine schedule), capped at max_scheduled_inv_s: short runs cannot wait for the
  // learned variance to sharpen the surface (it takes NeuS ~100k steps). 0: learned only.
  float sharpness = 0.5f;
  float max_scheduled_inv_s = 256.f;
  float anneal_fraction = 0.5f;         // NeuS cos_anneal ramps 0 -> 1 over this share of the steps
  float prune_start_fraction = 0.3f;    // occupancy pruning of the SDF's interior starts here
  std::uint32_t occupancy_interval = 100;
  // Steps fitting the SDF to the visual hull's truncated signed distance before rendering starts,
  // so NeuS refines the hull's shape instead of growing one from a sphere. Off by default: with
  // the mask term at weight 1 the sphere start was as good and faster (demo cat, 300 steps:
  // 0.235 % of the diagonal in 195 s from the sphere, 0.267 % in 271 s with 100 fit steps).
  std::uint32_t hull_fit_steps = 0;
  std::uint32_t checkpoint_interval = 250;  // 0: none
  unsigned seed = 1;
  // The band holds the rays that shape the silhouette, so it gets a larger share than the
  // selection's defaults; background rays beyond the band miss the hull and are redrawn.
  RaySampleOptions ray_options{0.70f, 0.25f, 0.05f};
  RayPoolOptions pool_options;
  void validate() const;  // InputError naming the field
};
json to_json(const NeusTrainingOptions& o);

// What the trainer reads of the scene: the images and masks of the training views, the visual
// hull (dilated: slack for the sampler) and the normalisation to the unit sphere.
struct NeusTrainingData {
  io::Scene scene;
  std::vector<std::vector<std::uint8_t>> rgb;    // per camera, width * height * 3 (empty: not loaded)
  std::vector<std::vector<std::uint8_t>> masks;  // per camera, width * height
  std::vector<std::uint32_t> train_views, held_out_views;
  OccupancyGrid hull;        // dilated: where rays take samples
  OccupancyGrid tight_hull;  // as carved: the shape the SDF is first fitted to
  Normalisation norm;
  // Pixels a ray pool's band must reach beyond the mask so that band rays cover every cell of the
  // (dilated) hull: cells the masks alone keep but no ray sees would stay unsupervised and show
  // up as a false surface at the hull's boundary.
  int band_px = 0;
};
// Loads images and masks (cameras without a mask or image are skipped with a warning), carves the
// hull, dilates it by `hull_slack_cells`, normalises, and sizes the band: the mask dilation plus the
// slack cells' largest projected size over the views, plus one pixel. Every `hold_out_every`-th view (index % k == k - 1) is held out for
// evaluation; 0 holds out none. InputError when no view is left to train on.
NeusTrainingData load_neus_training_data(const io::Scene& scene, const VisualHullOptions& hull_options,
                                         int hold_out_every);

constexpr std::uint32_t kHistoryEvery = 10;  // steps between the loss curve's points

struct NeusStepReport {
  std::uint32_t step = 0;         // steps done
  double loss = 0, colour_l1 = 0, mask_bce = 0, eikonal = 0, psnr = 0;
  float inv_s = 0, lr = 0;
  double seconds = 0;             // training time so far (excludes callbacks)
  double rays_per_second = 0;
  std::uint32_t skipped_steps = 0;  // non-finite gradients (the optimiser skipped them)
};

json to_json(const NeusStepReport& r);
NeusStepReport step_report_from_json(const json& j);  // json::exception on a missing field

// What a NeuS checkpoint holds besides its configuration, read and checked for form (tensors
// present, fields of the right types) before anything is applied; InputError naming the file.
struct NeusCheckpointState {
  std::vector<std::pair<std::string, std::vector<float>>> params;  // hash_table (when used), sdf, colour
  nn::Adam::State table_adam, sdf_adam, colour_adam;
  std::vector<float> occupancy;
  std::uint32_t step = 0, variance_t = 0;
  double seconds = 0, variance = 0, variance_m = 0, variance_v = 0;
  NeusStepReport last;
  std::vector<NeusStepReport> history;
};
NeusCheckpointState parse_neus_checkpoint(const nn::WeightsFile& file, const std::filesystem::path& path, bool has_table);

class NeusTrainer {
 public:
  NeusTrainer(gpu::Context& context, const NeusTrainingData& data, const NeusFieldConfig& field,
              const NeusTrainingOptions& options);
  ~NeusTrainer();

  std::uint32_t step() const { return step_; }
  // The last step's report, and the loss curve (every kHistoryEvery-th step and the last one);
  // both survive a checkpoint.
  const NeusStepReport& last_report() const { return last_; }
  const std::vector<NeusStepReport>& history() const { return history_; }
  const NeusTrainingOptions& options() const { return options_; }
  NeusField& field() { return *field_; }
  const OccupancyGrid& occupancy() const { return occupancy_; }
  float inv_s() const;  // the one rendering uses: max(learned, scheduled floor)
  float finite_difference_step() const;  // h at the current step (unit coordinates)

  // Trains until `until` steps are done (capped at options.steps). `after_step`, when set, runs
  // after every step and may stop training by returning false. Checkpoints go to `checkpoint`
  // (when not empty) every checkpoint_interval steps and at the end.
  NeusStepReport train(std::uint32_t until, const std::filesystem::path& checkpoint = {},
                       const std::function<bool(const NeusStepReport&)>& after_step = {});

  // Re-derives the occupancy grid from the SDF: hull cells whose centre is deeper inside than a
  // band of two cell diagonals are dropped (rays need no samples there).
  void update_occupancy();

  // The hull fit above (run by train() before step 0); returns the final mean squared error in
  // unit coordinates.
  double fit_to_hull();

  void save_checkpoint(const std::filesystem::path& path) const;
  // Restores a checkpoint written with the same field configuration, options and format version;
  // returns false (and changes nothing) when it was written for anything else. InputError (and
  // nothing changed) for a broken file.
  bool load_checkpoint(const std::filesystem::path& path);

 private:
  struct HostBatch;
  void build_batch(HostBatch& host) const;
  float learned_inv_s() const;
  float sharpness_floor() const;
  NeusStepReport train_step();

  gpu::Context& context_;
  const NeusTrainingData& data_;
  NeusFieldConfig field_config_;
  NeusTrainingOptions options_;
  RayPool pool_;
  OccupancyGrid occupancy_;
  std::unique_ptr<NeusField> field_;
  std::unique_ptr<NeusField::Batch> batch_;
  std::unique_ptr<nn::Adam> adam_table_, adam_sdf_, adam_colour_;
  std::unique_ptr<gpu::Buffer<float>> dist_, colour_, opacity_, grad_colour_, grad_opacity_, grad_sdf_, grad_cos_,
      grad_rgb_, grad_inv_s_;
  std::unique_ptr<gpu::Buffer<glm::vec4>> target_, loss_partials_;
  std::uint32_t step_ = 0;
  double seconds_ = 0;
  NeusStepReport last_;
  std::vector<NeusStepReport> history_;
  std::uint32_t skipped_ = 0;
  // The inverse variance's parameter and its Adam moments (host side: one scalar).
  double variance_ = 0, variance_m_ = 0, variance_v_ = 0;
  std::uint32_t variance_t_ = 0;
};

}  // namespace nf::neus
