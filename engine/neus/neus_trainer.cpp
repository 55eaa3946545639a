#include "engine/neus/neus_trainer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/parallel.hpp"
#include "engine/core/random.hpp"
#include "engine/geometry/distance_transform.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/gpu/context.hpp"
#include "engine/io/image.hpp"
#include "engine/io/mask_agreement.hpp"
#include "engine/io/view_split.hpp"
#include "engine/nn/training_checkpoint.hpp"
#include "engine/nn/weights_io.hpp"

namespace nf::neus {
namespace {

constexpr float kInvSMin = 1e-6f, kInvSMax = 1e6f;  // NeuS: inv_s = exp(10 v), clipped
constexpr int kCheckpointVersion = 1;

std::uint64_t mix(std::uint64_t a, std::uint64_t b) {
  return mix64(a * kGoldenGamma ^ (b + 0x632BE59BD9B4E019ull) * 0xD1B54A32D192ED03ull);
}
float unit_float(std::uint64_t bits) { return float(bits >> 40) * (1.f / 16777216.f); }  // [0, 1)

nn::AdamConfig adam_config() { return {0.9f, 0.99f, 1e-15f, 0.f}; }  // instant-nsr-pl's settings


}  // namespace

void NeusTrainingOptions::validate() const {
  const auto fail = [](const std::string& m) { throw InputError("neus training options: " + m); };
  if (steps == 0) fail("steps must be > 0");
  if (rays == 0 || rays > (1u << 20)) fail("rays must be in [1, 2^20]");
  if (samples_per_ray == 0 || samples_per_ray > 1024) fail("samples_per_ray must be in [1, 1024]");
  if (std::uint64_t(rays) * samples_per_ray > (1ull << 22)) fail("rays x samples_per_ray must be <= 2^22");
  if (fine_samples >= samples_per_ray) fail("fine_samples must be below samples_per_ray (the rest are coarse)");
  if (!(lr > 0 && std::isfinite(lr))) fail("lr must be finite and positive");
  if (!(variance_lr >= 0 && std::isfinite(variance_lr))) fail("variance_lr must be finite and >= 0");
  if (!(lr_floor >= 0 && lr_floor <= 1)) fail("lr_floor must lie in [0, 1]");
  if (!(weights.colour >= 0 && weights.mask >= 0 && eikonal >= 0)) fail("loss weights must be >= 0");
  if (!(anneal_fraction >= 0 && anneal_fraction <= 1)) fail("anneal_fraction must lie in [0, 1]");
  if (!(prune_start_fraction >= 0)) fail("prune_start_fraction must be >= 0");
  if (!std::isfinite(init_variance)) fail("init_variance must be finite");
}

json to_json(const NeusTrainingOptions& o) {
  return {{"steps", o.steps},
          {"rays", o.rays},
          {"samples_per_ray", o.samples_per_ray},
          {"fine_samples", o.fine_samples},
          {"lr", o.lr},
          {"variance_lr", o.variance_lr},
          {"warmup", o.warmup},
          {"lr_floor", o.lr_floor},
          {"colour_weight", o.weights.colour},
          {"mask_weight", o.weights.mask},
          {"eikonal_weight", o.eikonal},
          {"init_variance", o.init_variance},
          {"sharpness", o.sharpness},
          {"max_scheduled_inv_s", o.max_scheduled_inv_s},
          {"anneal_fraction", o.anneal_fraction},
          {"prune_start_fraction", o.prune_start_fraction},
          {"occupancy_interval", o.occupancy_interval},
          {"hull_fit_steps", o.hull_fit_steps},
          {"seed", o.seed},
          {"ray_shares", {o.ray_options.inside_share, o.ray_options.band_share, o.ray_options.background_share}},
          {"band_px", o.pool_options.band_px}};
}

json to_json(const NeusStepReport& r) {
  return {{"step", r.step},         {"seconds", r.seconds},   {"loss", r.loss},   {"colour_l1", r.colour_l1},
          {"mask_bce", r.mask_bce}, {"eikonal", r.eikonal},   {"psnr", r.psnr},   {"inv_s", r.inv_s},
          {"lr", r.lr},             {"rays_per_second", r.rays_per_second}, {"skipped_steps", r.skipped_steps}};
}

NeusStepReport step_report_from_json(const json& j) {
  NeusStepReport r;
  r.step = j.at("step").get<std::uint32_t>();
  r.seconds = j.at("seconds").get<double>();
  r.loss = j.at("loss").get<double>();
  r.colour_l1 = j.at("colour_l1").get<double>();
  r.mask_bce = j.at("mask_bce").get<double>();
  r.eikonal = j.at("eikonal").get<double>();
  r.psnr = j.at("psnr").get<double>();
  r.inv_s = j.at("inv_s").get<float>();
  r.lr = j.at("lr").get<float>();
  r.rays_per_second = j.at("rays_per_second").get<double>();
  r.skipped_steps = j.at("skipped_steps").get<std::uint32_t>();
  return r;
}

namespace {

// Masks whose edges do not follow their photos' outlines (io/mask_agreement.hpp): all of them
// (another animal's, or a shifted order) or one far below the others (a mask of another photo). A
// warning only: a photo whose animal blends into its background has weak edges of its own.
void warn_about_foreign_masks(const io::Scene& scene, const NeusTrainingData& d, const std::vector<std::uint8_t>& usable) {
  std::vector<double> peak(scene.cameras.size(), std::nan(""));
  std::vector<double> known;
  for (std::size_t c = 0; c < scene.cameras.size(); ++c) {
    if (!usable[c]) continue;
    peak[c] = io::mask_edge_peak(d.rgb[c], d.masks[c], scene.cameras[c].width, scene.cameras[c].height);
    if (std::isfinite(peak[c])) known.push_back(peak[c]);
  }
  if (known.empty()) return;
  std::nth_element(known.begin(), known.begin() + std::ptrdiff_t(known.size() / 2), known.end());
  const double median = known[known.size() / 2];
  constexpr double kFollows = 1.8, kForeign = 1.3;
  if (median < kFollows)
    log::warn(scene.root.string(), ": the masks' edges do not follow the photos' outlines (median edge peak ", median,
              "; a photo's own mask scores 2.5 or more); check that each mask belongs to its photo (same animal, same order)");
  else
    for (std::size_t c = 0; c < scene.cameras.size(); ++c)
      if (std::isfinite(peak[c]) && peak[c] < kForeign)
        log::warn(scene.root.string(), ": camera '", scene.cameras[c].name, "': the edge of mask ", scene.cameras[c].mask.string(),
                  " does not follow its photo's outline (edge peak ", peak[c], ", the other views' median ", median,
                  "); is it the mask of another photo?");
}

}  // namespace

NeusTrainingData load_neus_training_data(const io::Scene& scene, const VisualHullOptions& hull_options,
                                         int hold_out_every) {
  NeusTrainingData d;
  d.scene = scene;
  const OccupancyGrid hull = carve_visual_hull(scene, hull_options);
  d.norm = normalise_to_unit_sphere(hull);
  constexpr int kSlackCells = 2;
  d.tight_hull = hull;
  d.hull = dilate(hull, kSlackCells);
  glm::dvec3 lo, hi;
  hull.occupied_bounds(lo, hi);
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const double slack = kSlackCells * glm::length(hull.cell_size());
  double px = 0;
  for (const io::Camera& cam : scene.cameras) {
    const double dist = glm::length(glm::dvec3(cam.camera_to_world[3]) - centre) - 0.5 * glm::length(hi - lo);
    px = std::max(px, slack * std::max(cam.fx, cam.fy) / std::max(dist, 1e-9 + slack));
  }
  d.band_px = hull_options.dilate_px + int(std::ceil(std::min(px, 256.0))) + 1;
  const std::size_t n = scene.cameras.size();
  d.rgb.resize(n);
  d.masks.resize(n);
  std::vector<std::uint8_t> usable(n, 0);
  for_each_dynamic(int(n), [&](int ci) {
    {
      const std::size_t c = std::size_t(ci);
      const io::Camera& cam = scene.cameras[c];
      if (cam.mask.empty() || cam.image.empty()) return;
      const io::Image image = io::read_image(cam.image), mask = io::read_image(cam.mask);
      for (const io::Image* im : {&image, &mask})
        if (im->width != cam.width || im->height != cam.height)
          throw InputError(scene.root.string() + ": camera '" + cam.name + "': " +
                           (im == &image ? cam.image : cam.mask).string() + " is " + std::to_string(im->width) + "x" +
                           std::to_string(im->height) + ", the camera is " + std::to_string(cam.width) + "x" +
                           std::to_string(cam.height));
      std::vector<std::uint8_t>& rgb = d.rgb[c];
      const std::size_t pixels = std::size_t(cam.width) * cam.height;
      rgb.resize(pixels * 3);
      for (std::size_t p = 0; p < pixels; ++p)
        for (std::uint32_t k = 0; k < 3; ++k) {
          const float v = image.pixels[p * image.channels + std::min(k, image.channels >= 3 ? k : 0u)];
          rgb[p * 3 + k] = std::uint8_t(std::lround(std::clamp(v, 0.f, 1.f) * 255.f));
        }
      d.masks[c] = io::mask_of(mask);
      usable[c] = 1;
    }
  });
  warn_about_foreign_masks(scene, d, usable);
  for (std::size_t c = 0; c < n; ++c) {
    if (!usable[c]) {
      log::warn(scene.root.string(), ": camera '", scene.cameras[c].name,
                "' lacks an image or a mask; the surface stage does not train on it");
      continue;
    }
    const bool held = io::is_held_out(std::uint32_t(c), hold_out_every);
    (held ? d.held_out_views : d.train_views).push_back(std::uint32_t(c));
  }
  if (d.train_views.empty())
    throw InputError(scene.root.string() + ": no camera with both an image and a mask is left to train the surface on");
  return d;
}

struct NeusTrainer::HostBatch {
  std::vector<glm::vec4> samples, dirs, target;
  std::vector<float> dist;
  std::uint32_t inside = 0;
};

NeusTrainer::NeusTrainer(gpu::Context& context, const NeusTrainingData& data, const NeusFieldConfig& field,
                         const NeusTrainingOptions& options)
    : context_(context), data_(data), field_config_(field), options_(options) {
  options_.validate();
  log::debug("neus: band of ", std::max(options_.pool_options.band_px, data.band_px), " px around the masks");
  RayPoolOptions pool_options = options_.pool_options;
  pool_options.band_px = std::max(pool_options.band_px, data.band_px);
  pool_ = build_ray_pool(data.scene, data.masks, pool_options);
  std::vector<std::uint8_t> training(data.scene.cameras.size(), 0);
  for (const std::uint32_t c : data.train_views) training[c] = 1;
  for (std::size_t c = 0; c < pool_.cameras.size(); ++c)
    if (!training[c])
      for (auto& pixels : pool_.cameras[c].pixels) pixels.clear();
  occupancy_ = data.hull;
  field_ = std::make_unique<NeusField>(context, field_config_, options_.seed);
  batch_ = std::make_unique<NeusField::Batch>(*field_, options_.rays, options_.samples_per_ray);
  if (field_->has_table())
    adam_table_ = std::make_unique<nn::Adam>(context, field_->table().size(), adam_config(), std::vector<nn::ParamGroup>{});
  adam_sdf_ = std::make_unique<nn::Adam>(context, field_->sdf().parameters().size(), adam_config(), std::vector<nn::ParamGroup>{});
  adam_colour_ = std::make_unique<nn::Adam>(context, field_->colour().parameters().size(), adam_config(), std::vector<nn::ParamGroup>{});
  const std::uint64_t n = batch_->n, r = options_.rays;
  dist_ = std::make_unique<gpu::Buffer<float>>(context, n, "neus dist");
  colour_ = std::make_unique<gpu::Buffer<float>>(context, r * 3, "neus ray colour");
  opacity_ = std::make_unique<gpu::Buffer<float>>(context, r, "neus ray opacity");
  grad_colour_ = std::make_unique<gpu::Buffer<float>>(context, r * 3, "neus ray colour gradient");
  grad_opacity_ = std::make_unique<gpu::Buffer<float>>(context, r, "neus ray opacity gradient");
  grad_sdf_ = std::make_unique<gpu::Buffer<float>>(context, n, "neus sdf gradient");
  grad_cos_ = std::make_unique<gpu::Buffer<float>>(context, n, "neus cos gradient");
  grad_rgb_ = std::make_unique<gpu::Buffer<float>>(context, n * 3, "neus rgb gradient");
  grad_inv_s_ = std::make_unique<gpu::Buffer<float>>(context, 1, "neus inv_s gradient");
  target_ = std::make_unique<gpu::Buffer<glm::vec4>>(context, r, "neus ray targets");
  loss_partials_ = std::make_unique<gpu::Buffer<glm::vec4>>(context, render_loss_partial_count(options_.rays), "neus loss partials");
  variance_ = options_.init_variance;
}

NeusTrainer::~NeusTrainer() = default;

float NeusTrainer::learned_inv_s() const {
  return std::clamp(float(std::exp(10.0 * variance_)), kInvSMin, kInvSMax);
}

float NeusTrainer::sharpness_floor() const {
  if (!(options_.sharpness > 0)) return 0.f;
  return std::min(options_.sharpness / finite_difference_step(), options_.max_scheduled_inv_s);
}

float NeusTrainer::inv_s() const { return std::max(learned_inv_s(), sharpness_floor()); }

float NeusTrainer::finite_difference_step() const {
  if (field_config_.encoding != FieldEncoding::HashGrid) return 1.f / 512.f;
  // Coarse to fine: the step follows the hash grid's resolution reached at this point of the run
  // (wide steps early smooth the gradients, as instant-nsr-pl's progressive finite differences).
  const double progress = std::min(1.0, double(step_) / (0.5 * options_.steps));
  const double res = field_config_.hash.base_resolution *
                     std::pow(double(field_config_.hash.max_resolution) / field_config_.hash.base_resolution, progress);
  return float(1.0 / res);  // half a cell of the hash grid at `res` ([0, 1] spans 2 unit lengths)
}

void NeusTrainer::build_batch(HostBatch& host) const {
  const std::uint32_t R = options_.rays, S = options_.samples_per_ray;
  std::vector<Ray> rays;
  rays.reserve(R);
  for (std::uint32_t attempt = 0; rays.size() < R && attempt < 16; ++attempt) {
    const unsigned seed = unsigned(mix(mix(options_.seed, step_), attempt));
    for (const Ray& ray : sample_rays(pool_, data_.scene, data_.norm, &occupancy_, R, seed, options_.ray_options))
      if (ray.hit() && rays.size() < R) rays.push_back(ray);
  }
  if (rays.empty()) throw InputError("neus: no training ray crosses the occupied volume (empty masks?)");
  for (std::size_t i = 0; rays.size() < R; ++i) rays.push_back(rays[i]);  // rare: pad with repeats
  host.samples.assign(std::size_t(R) * S, glm::vec4(0.f));
  host.dist.assign(std::size_t(R) * S, 0.f);
  host.dirs.resize(R);
  host.target.resize(R);
  host.inside = 0;
  // Coarse samples: stratified over each ray's occupied stretches.
  const std::uint32_t fine = options_.fine_samples, coarse = S - fine;
  std::vector<std::vector<float>> coarse_t(R);
  std::vector<float> step(R), dist;
  for (std::uint32_t i = 0; i < R; ++i) {
    const Ray& ray = rays[i];
    const float jitter = unit_float(mix(mix(options_.seed, step_) ^ 0xA5A5A5A5ull, i));
    stratified_samples(occupied_segments(ray.origin, ray.direction, data_.norm, occupancy_, options_.ray_options.near_epsilon),
                       coarse, jitter, coarse_t[i], dist);
    if (coarse_t[i].size() != coarse)  // rounding left no occupied length: spread over [near, far]
      stratified_samples({{ray.near, ray.far}}, coarse, jitter, coarse_t[i], dist);
    step[i] = dist.empty() ? 0.f : dist[0];
  }
  // Fine samples: NeuS up-sampling where the current surface is (one SDF inference at the coarse
  // samples), so a sharp surface still has samples inside its transition.
  std::vector<float> coarse_sdf;
  if (fine > 0) {
    std::vector<glm::vec3> points;
    points.reserve(std::size_t(R) * coarse);
    for (std::uint32_t i = 0; i < R; ++i)
      for (const float tj : coarse_t[i]) points.push_back(rays[i].origin + tj * rays[i].direction);
    coarse_sdf = field_->sdf_at(points);
  }
  const float up_inv_s = std::max(64.f, inv_s());
  std::vector<float> t, sdf(coarse), fine_t;
  for (std::uint32_t i = 0; i < R; ++i) {
    const Ray& ray = rays[i];
    if (fine > 0) {
      std::copy_n(coarse_sdf.begin() + std::ptrdiff_t(i) * coarse, coarse, sdf.begin());
      const float jitter = unit_float(mix(mix(options_.seed, step_) ^ 0x5A5A5A5Aull, i));
      fine_t = upsample_positions(coarse_t[i], sdf, 1.5f * step[i], up_inv_s, fine, jitter);
      if (fine_t.size() != fine) stratified_samples({{ray.near, ray.far}}, fine, jitter, fine_t, dist);
    }
    merge_samples(coarse_t[i], fine_t, step[i], t, dist);
    for (std::uint32_t j = 0; j < S; ++j) {
      host.samples[std::size_t(i) * S + j] = glm::vec4(ray.origin + t[j] * ray.direction, 0.f);
      host.dist[std::size_t(i) * S + j] = dist[j];
    }
    host.dirs[i] = glm::vec4(ray.direction, 0.f);
    const std::uint8_t* px = data_.rgb[ray.camera].data() + std::size_t(ray.pixel) * 3;
    const float mask = data_.masks[ray.camera][ray.pixel] ? 1.f : 0.f;
    host.target[i] = glm::vec4(px[0] / 255.f, px[1] / 255.f, px[2] / 255.f, mask);
    host.inside += mask > 0.5f;
  }
}

NeusStepReport NeusTrainer::train_step() {
  const auto start = std::chrono::steady_clock::now();
  HostBatch host;
  build_batch(host);
  NeusField::Batch& b = *batch_;
  b.samples.upload(host.samples);
  b.dirs.upload(host.dirs);
  dist_->upload(host.dist);
  target_->upload(host.target);

  const float h = finite_difference_step();
  const float s = inv_s();
  const float anneal = options_.anneal_fraction > 0
                           ? std::min(1.f, float(step_) / (options_.anneal_fraction * float(options_.steps)))
                           : 1.f;
  const nn::LearningRateSchedule schedule{options_.lr, options_.warmup, options_.steps, options_.lr_floor};
  const float lr = schedule.at(step_);
  const VolumeRenderShape shape{options_.rays, options_.samples_per_ray};
  const VolumeRenderParams params{s, anneal, 0};
  const VolumeRenderInputBuffers inputs{b.sdf.whole(), b.cos.whole(), dist_->whole(), b.rgb.whole()};

  gpu::Stream stream(context_);
  field_->forward(stream, b, h);
  {
    gpu::ScopedPass pass(stream, "neus render and loss");
    volume_render_forward(stream, shape, params, inputs, {colour_->whole(), opacity_->whole()});
    render_loss(stream, options_.rays, host.inside, options_.weights, colour_->whole(), opacity_->whole(),
                target_->whole(), grad_colour_->whole(), grad_opacity_->whole(), loss_partials_->whole());
  }
  {
    gpu::ScopedPass pass(stream, "neus render backward");
    volume_render_backward(stream, shape, params, inputs, grad_colour_->whole(), grad_opacity_->whole(),
                           {grad_sdf_->whole(), grad_cos_->whole(), grad_rgb_->whole(), grad_inv_s_->whole()});
  }
  field_->backward(stream, b, h, options_.eikonal, grad_sdf_->whole(), grad_cos_->whole(), grad_rgb_->whole());
  {
    gpu::ScopedPass pass(stream, "neus optimiser");
    if (adam_table_) adam_table_->step(stream, field_->table().whole(), field_->table_gradient().whole(), lr);
    adam_sdf_->step(stream, field_->sdf().parameters().whole(), field_->sdf().gradients().whole(), lr);
    adam_colour_->step(stream, field_->colour().parameters().whole(), field_->colour().gradients().whole(), lr);
  }
  stream.submit_and_wait();

  // The inverse variance: one scalar, Adam on the host; zero gradient where the clip is active.
  const float g_inv_s = grad_inv_s_->download()[0];
  const double raw = std::exp(10.0 * variance_);
  // Zero gradient where the clip is active or the schedule's floor decides.
  const bool gated = !(raw > kInvSMin && raw < kInvSMax) || learned_inv_s() < sharpness_floor();
  const double g = double(g_inv_s) * 10.0 * raw;
  if (!gated && std::isfinite(g)) {  // no update at all while gated: momentum would keep moving v
    ++variance_t_;
    variance_m_ = 0.9 * variance_m_ + 0.1 * g;
    variance_v_ = 0.99 * variance_v_ + 0.01 * g * g;
    const double mh = variance_m_ / (1.0 - std::pow(0.9, variance_t_));
    const double vh = variance_v_ / (1.0 - std::pow(0.99, variance_t_));
    variance_ -= double(options_.variance_lr) * (lr / options_.lr) * mh / (std::sqrt(vh) + 1e-15);
  }

  const RenderLossTotals totals = sum_render_loss(loss_partials_->download(), options_.rays);
  double eikonal = 0;
  for (const float e : b.eikonal_partials.download()) eikonal += e;
  eikonal /= double(b.n);
  ++step_;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  seconds_ += elapsed;
  skipped_ = adam_sdf_->counters().skipped;
  skipped_ = std::max(skipped_, adam_colour_->counters().skipped);
  if (adam_table_) skipped_ = std::max(skipped_, adam_table_->counters().skipped);

  NeusStepReport r;
  r.step = step_;
  r.colour_l1 = totals.colour_l1 / std::max(1.0, totals.inside);
  r.mask_bce = totals.bce;
  r.eikonal = eikonal;
  r.loss = totals.loss(options_.weights) + options_.eikonal * eikonal;
  r.psnr = totals.psnr();
  r.inv_s = inv_s();
  r.lr = lr;
  r.seconds = seconds_;
  r.rays_per_second = options_.rays / std::max(1e-9, elapsed);
  r.skipped_steps = skipped_;
  last_ = r;
  if (step_ % kHistoryEvery == 0 || step_ == options_.steps) history_.push_back(r);
  return r;
}

void NeusTrainer::update_occupancy() {
  const OccupancyGrid& hull = data_.hull;
  std::vector<glm::vec3> centres;
  std::vector<std::size_t> cells;
  for (int k = 0; k < hull.dims.z; ++k)
    for (int j = 0; j < hull.dims.y; ++j)
      for (int i = 0; i < hull.dims.x; ++i)
        if (hull.at(i, j, k)) {
          centres.push_back(glm::vec3(data_.norm.to_unit(hull.cell_centre(i, j, k))));
          cells.push_back(hull.index(i, j, k));
        }
  const std::vector<float> sdf = field_->sdf_at(centres);
  const float band = float(2.0 * glm::length(hull.cell_size()) * data_.norm.scale);
  OccupancyGrid next = hull;
  std::size_t kept = 0;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const bool keep = !(sdf[c] < -band);  // NaN keeps the cell
    next.occupied[cells[c]] = keep;
    kept += keep;
  }
  if (kept == 0) return;  // a field that is all interior has not formed yet: keep the hull
  occupancy_ = std::move(next);
}

double NeusTrainer::fit_to_hull() {
  const OccupancyGrid& hull = data_.tight_hull;
  const glm::ivec3 dims = hull.dims;
  const glm::dvec3 cs = hull.cell_size();
  // Signed distance between cell centres (negative inside), in unit coordinates, truncated.
  std::vector<std::uint8_t> outside(hull.occupied.size());
  for (std::size_t i = 0; i < outside.size(); ++i) outside[i] = !hull.occupied[i];
  const std::vector<float> to_inside = geometry::distance_transform(hull.occupied, dims, glm::vec3(cs));
  const std::vector<float> to_outside = geometry::distance_transform(outside, dims, glm::vec3(cs));
  const float half = float(0.5 * glm::length(cs) / std::sqrt(3.0)), scale = float(data_.norm.scale);
  constexpr float kTruncation = 0.1f;  // unit coordinates: far values matter little and train slowly
  std::vector<float> sdf(hull.occupied.size());
  std::vector<std::uint32_t> near_surface;
  for (std::size_t i = 0; i < sdf.size(); ++i) {
    const float d = hull.occupied[i] ? -(to_outside[i] - half) : to_inside[i] - half;
    sdf[i] = std::clamp(d * scale, -kTruncation, kTruncation);
    if (std::fabs(d) < 2.f * float(glm::length(cs))) near_surface.push_back(std::uint32_t(i));
  }
  if (near_surface.empty()) return 0.0;
  const auto lookup = [&](const glm::dvec3& world) {  // trilinear over cell centres, clamped
    const glm::dvec3 g = glm::clamp((world - hull.lo) / cs - 0.5, glm::dvec3(0.0), glm::dvec3(dims - 1) - 1e-9);
    const glm::ivec3 c = glm::ivec3(glm::floor(g));
    const glm::dvec3 f = g - glm::dvec3(c);
    double v = 0;
    for (int corner = 0; corner < 8; ++corner) {
      const glm::ivec3 o(corner & 1, (corner >> 1) & 1, corner >> 2);
      const glm::ivec3 q = glm::min(c + o, dims - 1);
      const double w = (o.x ? f.x : 1 - f.x) * (o.y ? f.y : 1 - f.y) * (o.z ? f.z : 1 - f.z);
      v += w * sdf[hull.index(q.x, q.y, q.z)];
    }
    return float(v);
  };

  NeusField::Batch& b = *batch_;
  const std::uint32_t n = b.n;
  std::vector<glm::vec4> points(n), dirs(b.rays, glm::vec4(0.f, 0.f, -1.f, 0.f));
  std::vector<float> target(n), grad(n);
  b.dirs.upload(dirs);
  grad_cos_->fill_u32(0);
  grad_rgb_->fill_u32(0);
  double mse = 0;
  for (std::uint32_t step = 0; step < options_.hull_fit_steps; ++step) {
    // Half the points anywhere in the hull's box, half in cells near its boundary.
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint64_t r = mix(mix(options_.seed ^ 0x5EEDull, step), i);
      const glm::dvec3 u(unit_float(r), unit_float(mix(r, 1)), unit_float(mix(r, 2)));
      glm::dvec3 world;
      if (i % 2 == 0) {
        world = hull.lo + u * (hull.hi - hull.lo);
      } else {
        const std::size_t cell = near_surface[std::size_t(mix(r, 3) % near_surface.size())];
        const int x = int(cell % std::size_t(dims.x)), y = int(cell / std::size_t(dims.x) % std::size_t(dims.y)),
                  z = int(cell / (std::size_t(dims.x) * std::size_t(dims.y)));
        world = hull.cell_lo(x, y, z) + u * cs;
      }
      points[i] = glm::vec4(glm::vec3(data_.norm.to_unit(world)), 0.f);
      target[i] = lookup(world);
    }
    b.samples.upload(points);
    const float h = finite_difference_step();
    gpu::Stream stream(context_);
    field_->forward(stream, b, h);
    stream.submit_and_wait();
    const std::vector<float> pred = b.sdf.download();
    mse = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
      const double e = double(pred[i]) - target[i];
      mse += e * e;
      grad[i] = float(2.0 * e / n);
    }
    mse /= n;
    grad_sdf_->upload(grad);
    field_->backward(stream, b, h, options_.eikonal, grad_sdf_->whole(), grad_cos_->whole(), grad_rgb_->whole());
    if (adam_table_) adam_table_->step(stream, field_->table().whole(), field_->table_gradient().whole(), options_.lr);
    adam_sdf_->step(stream, field_->sdf().parameters().whole(), field_->sdf().gradients().whole(), options_.lr);
    stream.submit_and_wait();
  }
  log::debug("neus: fitted the visual hull in ", options_.hull_fit_steps, " steps, rms ", std::sqrt(mse), " (unit)");
  return mse;
}

NeusStepReport NeusTrainer::train(std::uint32_t until, const std::filesystem::path& checkpoint,
                                  const std::function<bool(const NeusStepReport&)>& after_step) {
  until = std::min(until, options_.steps);
  NeusStepReport report;
  report.step = step_;
  const std::uint32_t prune_from = std::uint32_t(options_.prune_start_fraction * float(options_.steps));
  if (step_ == 0 && until > 0 && options_.hull_fit_steps > 0) {  // a resumed run has done it already
    const auto start = std::chrono::steady_clock::now();
    fit_to_hull();
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  while (step_ < until) {
    if (options_.occupancy_interval > 0 && step_ >= prune_from && step_ > 0 &&
        (step_ - prune_from) % options_.occupancy_interval == 0) {
      const auto start = std::chrono::steady_clock::now();
      update_occupancy();
      seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    report = train_step();
    if (!checkpoint.empty() && nn::checkpoint_due(step_, until, options_.checkpoint_interval)) save_checkpoint(checkpoint);
    if (after_step && !after_step(report)) break;
  }
  return report;
}

namespace {
nn::CheckpointIdentity checkpoint_identity(const NeusFieldConfig& field, const NeusTrainingOptions& options) {
  return {"neus checkpoint", kCheckpointVersion, to_json(field), to_json(options)};
}
}  // namespace

void NeusTrainer::save_checkpoint(const std::filesystem::path& path) const {
  json history = json::array();
  for (const NeusStepReport& r : history_) history.push_back(to_json(r));
  nn::WeightsFile file = nn::checkpoint_file(checkpoint_identity(field_config_, options_), {step_, seconds_, to_json(last_), std::move(history)});
  file.config["variance"] = variance_;
  file.config["variance_adam"] = {variance_m_, variance_v_, variance_t_};
  const auto add = [&](const std::string& name, std::vector<float> values) {
    const std::uint64_t count = values.size();
    file.tensors.push_back({name, {count}, std::move(values)});
  };
  for (auto& [name, values] : field_->save_parameters()) add(name, std::move(values));
  const auto add_adam = [&](const std::string& name, const nn::Adam* adam) {
    if (adam) nn::add_state_tensors(adam->save_state(), name, file);
  };
  add_adam("adam.hash_table", adam_table_.get());
  add_adam("adam.sdf", adam_sdf_.get());
  add_adam("adam.colour", adam_colour_.get());
  add("occupancy", std::vector<float>(occupancy_.occupied.begin(), occupancy_.occupied.end()));
  nn::save_weights(path, file);
}

NeusCheckpointState parse_neus_checkpoint(const nn::WeightsFile& file, const std::filesystem::path& path, bool has_table) {
  NeusCheckpointState s;
  for (const std::string name : {"hash_table", "sdf", "colour"})
    if (name != "hash_table" || has_table) s.params.emplace_back(name, file.tensor(name, path).values);
  const auto adam_state = [&](const std::string& name) { return nn::state_from_tensors(file, name, path); };
  if (has_table) s.table_adam = adam_state("adam.hash_table");
  s.sdf_adam = adam_state("adam.sdf"), s.colour_adam = adam_state("adam.colour");
  s.occupancy = file.tensor("occupancy", path).values;
  const nn::CheckpointProgress progress = nn::checkpoint_progress(file, path);
  s.step = progress.step, s.seconds = progress.seconds;
  try {
    const json& c = file.config;
    s.variance = c.at("variance").get<double>();
    s.variance_m = c.at("variance_adam").at(0).get<double>();
    s.variance_v = c.at("variance_adam").at(1).get<double>();
    s.variance_t = c.at("variance_adam").at(2).get<std::uint32_t>();
    s.last = step_report_from_json(progress.last);
    for (const json& r : progress.history) s.history.push_back(step_report_from_json(r));
  } catch (const json::exception& e) {
    throw InputError(path.string() + ": " + e.what());
  }
  return s;
}

bool NeusTrainer::load_checkpoint(const std::filesystem::path& path) {
  const std::optional<nn::WeightsFile> file = nn::load_checkpoint_of(path, checkpoint_identity(field_config_, options_));
  if (!file) return false;
  // Everything is read and checked before anything is applied.
  NeusCheckpointState s = parse_neus_checkpoint(*file, path, adam_table_ != nullptr);
  if (s.occupancy.size() != occupancy_.occupied.size())
    throw InputError(path.string() + ": the occupancy grid has " + std::to_string(s.occupancy.size()) + " cells, the scene's " +
                     std::to_string(occupancy_.occupied.size()));
  field_->load_parameters(s.params);
  if (adam_table_) adam_table_->load_state(s.table_adam);
  adam_sdf_->load_state(s.sdf_adam);
  adam_colour_->load_state(s.colour_adam);
  for (std::size_t i = 0; i < s.occupancy.size(); ++i) occupancy_.occupied[i] = s.occupancy[i] != 0.f;
  step_ = s.step, seconds_ = s.seconds, variance_ = s.variance;
  variance_m_ = s.variance_m, variance_v_ = s.variance_v, variance_t_ = s.variance_t;
  last_ = s.last, history_ = std::move(s.history);
  return true;
}

}  // namespace nf::neus
