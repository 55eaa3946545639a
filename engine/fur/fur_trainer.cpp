#include "engine/fur/fur_trainer.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <unordered_set>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/random.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/fur/fur_resolution.hpp"
#include "engine/fur/prior_training.hpp"
#include "engine/fur/strand_chamfer.hpp"
#include "engine/fur/strand_losses.hpp"
#include "engine/gpu/context.hpp"
#include "engine/nn/adam.hpp"
#include "engine/nn/training_checkpoint.hpp"
#include "engine/nn/weights_io.hpp"
#include "engine/splat/image_losses.hpp"
#include "engine/splat/rasterizer.hpp"

namespace nf::fur {
namespace {

constexpr int kCheckpointVersion = 2;  // 2: the warm-up's field and the length factors
constexpr std::uint32_t kHistoryEvery = 10;

// The near and far planes of a view: around the body's depth range, wide enough for the fur.
std::pair<double, double> depth_range(const FurView& v, double reach) {
  double lo = INFINITY, hi = 0;
  for (float d : v.body_depth)
    if (std::isfinite(d)) lo = std::min(lo, double(d)), hi = std::max(hi, double(d));
  if (!(hi > 0)) return {1e-3 * reach, 1e3 * reach};
  return {std::max(1e-6 * hi, lo - 2 * reach), hi + 2 * reach};
}

}  // namespace

json to_json(const FurLossWeights& w) {
  return {{"silhouette", w.silhouette}, {"orientation", w.orientation}, {"direction", w.direction}, {"chamfer", w.chamfer},
          {"penetration", w.penetration}, {"curvature", w.curvature},       {"envelope", w.envelope}};
}

void FurTrainingOptions::validate() const {
  const auto fail = [](const std::string& m) { throw InputError("fur training options: " + m); };
  if (strands < 1) fail("strands per step must be at least 1");
  if (!(lr > 0) || !(lr_floor >= 0 && lr_floor <= 1)) fail("lr must be positive and lr_floor in [0, 1]");
  if (!(strand_width >= 0)) fail("strand_width must be 0 (from the data) or positive");
  if (!(coverage > 0)) fail("coverage must be positive");
  if (!(resolved_fur_px >= 0 && std::isfinite(resolved_fur_px))) fail("resolved_fur_px must be finite and non-negative");
  if (!(lying_angle_deg >= 0 && lying_angle_deg <= 90)) fail("lying_angle_deg must be in [0, 90]");
  if (!(length_lr >= 0 && std::isfinite(length_lr))) fail("length_lr must be finite and non-negative");
  length_bounds.validate();
  for (double w : {weights.silhouette, weights.orientation, weights.direction, weights.chamfer, weights.penetration, weights.curvature,
                   weights.envelope})
    if (!(w >= 0 && std::isfinite(w))) fail("loss weights must be finite and non-negative");
}

json to_json(const FurTrainingOptions& o) {
  return {{"steps", o.steps},
          {"strands", o.strands},
          {"warm_steps", o.warm_steps},
          {"warm_start", o.warm_start},
          {"lying_angle_deg", o.lying_angle_deg},
          {"lr", o.lr},
          {"lr_floor", o.lr_floor},
          {"weight_decay", o.weight_decay},
          {"image_ramp_steps", o.image_ramp_steps},
          {"resolved_fur_px", o.resolved_fur_px},
          {"weights", to_json(o.weights)},
          {"chamfer_queries", o.chamfer_queries},
          {"strand_width", o.strand_width},
          {"coverage", o.coverage},
          {"train_decoder", o.train_decoder},
          {"length_lr", o.length_lr},
          {"length_bounds", {o.length_bounds.lo, o.length_bounds.hi}},
          {"seed", o.seed}};
}

json to_json(const FurStepReport& r) {
  json j{{"step", r.step},
         {"warm", r.warm},
         {"loss", r.loss},
         {"silhouette", r.silhouette},
         {"orientation", r.orientation},
         {"direction", r.direction},
         {"chamfer", r.chamfer},
         {"penetration", r.penetration},
         {"curvature", r.curvature},
         {"envelope", r.envelope},
         {"chamfer_unmatched", r.chamfer_unmatched},
         {"length_factor_mean", r.length_factor_mean},
         {"lr", r.lr},
         {"grad_norm", r.grad_norm},
         {"skipped_steps", r.skipped_steps},
         {"seconds", r.seconds}};
  if (r.image) j["view"] = r.view;
  if (!r.pass_seconds.is_null()) j["pass_seconds"] = r.pass_seconds;
  return j;
}

std::vector<std::uint32_t> sample_indices(std::uint64_t n, std::uint32_t count, std::uint64_t seed) {
  std::vector<std::uint32_t> out;
  if (count >= n) {
    out.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) out[i] = i;
    return out;
  }
  // Floyd's algorithm: count distinct values in O(count).
  std::mt19937_64 rng(seed);
  std::unordered_set<std::uint32_t> taken;
  taken.reserve(count * 2);
  for (std::uint64_t j = n - count; j < n; ++j) {
    const std::uint32_t t = std::uint32_t(std::uniform_int_distribution<std::uint64_t>(0, j)(rng));
    const std::uint32_t pick = taken.count(t) ? std::uint32_t(j) : t;
    taken.insert(pick);
    out.push_back(pick);
  }
  return out;
}

std::vector<float> lifted_strand_latent(StrandPrior& prior, double lying_angle_deg) {
  const double a = lying_angle_deg * M_PI / 180.0;
  std::vector<float> strand(std::size_t(kStrandPoints) * 3);
  for (std::uint32_t k = 0; k < kStrandPoints; ++k) {
    const double t = double(k) / kStrandSegments;
    strand[3 * k] = float(t * std::cos(a)), strand[3 * k + 1] = 0.f, strand[3 * k + 2] = float(t * std::sin(a));
  }
  return fit_latents(prior, strand, 300, 1e-2f, true).latents;
}

struct FurTrainer::Impl {
  Impl(gpu::Context& c, const FurTrainingData& d, FurField& field, const FurTrainingOptions& o)
      : batch(field, std::min<std::uint32_t>(o.strands, std::uint32_t(d.roots.size()))),
        rasterizer(c),
        loss_shape{batch.strands, kStrandPoints},
        loss_scratch(c, loss_shape),
        // Cells from the fur's area and the batch's points; the reach of the earlier fixed grid
        // (64 cells, 8 rings: an eighth of the box) kept.
        chamfer_grid(fur::chamfer_grid_for(d.lo, d.hi, std::uint64_t(batch.strands) * kStrandPoints, d.fur_area,
                                           double(std::max({d.hi.x - d.lo.x, d.hi.y - d.lo.y, d.hi.z - d.lo.z})) / 8)),
        chamfer_queries(std::min<std::uint64_t>(o.chamfer_queries, d.surface_points.size() / 3)),
        chamfer_scratch(c, std::uint64_t(batch.strands) * kStrandPoints, std::max<std::uint64_t>(1, chamfer_queries), chamfer_grid),
        guides(c, std::uint64_t(batch.strands) * 3, "fur guides"),
        lengths(c, batch.strands, "fur lengths"),
        sdf(c, d.bald_sdf.values, "bald sdf"),
        queries(c, std::max<std::uint64_t>(1, chamfer_queries) * 3, "chamfer queries"),
        envelope_scratch(c, loss_shape),
        envelope_sdf(c, d.envelope_sdf.values.empty() ? std::vector<float>{1.f} : d.envelope_sdf.values, "envelope sdf"),
        losses(c, 4, "fur image losses") {
    std::uint64_t most = 1;
    for (const auto* views : {&d.train, &d.held_out, &d.held_out_patches})
      for (const FurView& v : *views) most = std::max(most, v.pixels());
    if (d.patches) most = std::max(most, std::uint64_t(d.patches->patch_size()) * d.patches->patch_size());
    for (auto* b : {&image, &grad_image}) b->reset(new gpu::Buffer<float>(c, most * splat::kChannels, "fur image"));
    for (auto* b : {&mask, &weight, &angle, &confidence, &depth}) b->reset(new gpu::Buffer<float>(c, most, "fur view target"));
    grid.dims = {d.bald_sdf.grid.dims.x, d.bald_sdf.grid.dims.y, d.bald_sdf.grid.dims.z};
    grid.origin = {d.bald_sdf.grid.origin.x, d.bald_sdf.grid.origin.y, d.bald_sdf.grid.origin.z};
    grid.spacing = d.bald_sdf.grid.voxel;
    has_envelope = !d.envelope_sdf.values.empty();
    if (has_envelope) {
      envelope_grid.dims = {d.envelope_sdf.grid.dims.x, d.envelope_sdf.grid.dims.y, d.envelope_sdf.grid.dims.z};
      envelope_grid.origin = {d.envelope_sdf.grid.origin.x, d.envelope_sdf.grid.origin.y, d.envelope_sdf.grid.origin.z};
      envelope_grid.spacing = d.envelope_sdf.grid.voxel;
    }
  }
  FurField::Batch batch;
  splat::StrandRasterizer rasterizer;
  StrandLossShape loss_shape;
  StrandLossScratch loss_scratch;
  ChamferGrid chamfer_grid;
  std::uint64_t chamfer_queries;
  StrandChamferScratch chamfer_scratch;
  SdfGridRef grid;
  gpu::Buffer<float> guides, lengths, sdf, queries;
  StrandLossScratch envelope_scratch;  // the strand losses on M_NeuS's negated distance: only their penetration term is used
  gpu::Buffer<float> envelope_sdf, losses;
  SdfGridRef envelope_grid;
  bool has_envelope = false;
  std::unique_ptr<gpu::Buffer<float>> image, grad_image, mask, weight, angle, confidence, depth;
  std::unique_ptr<nn::Adam> adam, adam_decoder;
  std::uint32_t uploaded_view = ~0u;

  void upload_view(const FurView& v) {
    mask->upload(v.mask);
    weight->upload(v.silhouette_weight);
    angle->upload(v.gabor_angle);
    std::vector<float> c(v.pixels());
    for (std::size_t p = 0; p < c.size(); ++p) c[p] = v.gabor_confidence[p] * v.orientation_weight[p];
    confidence->upload(c);
    depth->upload(v.body_depth);
  }
};

FurTrainer::FurTrainer(gpu::Context& context, const FurTrainingData& data, StrandPrior& prior, const FurFieldConfig& field,
                       const FurTrainingOptions& options)
    : context_(context), data_(data), options_(options), field_config_(field) {
  options_.validate();
  if (data.roots.size() == 0) throw InputError("fur: there are no roots (every region is bald); there is no fur to grow");
  double total = 0;
  for (float l : data.roots.length) total += l;
  mean_root_length_ = total / double(data.roots.size());
  if (data.patches) {
    NF_CHECK(data.patches->size() == data.train.size(), "fur: a patch store of other views than the training views");
    for (std::uint32_t v = 0; v < data.train.size(); ++v)
      NF_CHECK(data.patches->camera(v) == data.train[v].camera, "fur: a patch store of other views than the training views");
  }
  for (std::uint32_t v = 0; v < data.train.size(); ++v) {
    const double px = fur_length_pixels(data.train[v], data.roots);
    resolution_.push_back({px, image_loss_weight(px, options_.resolved_fur_px)});
    if (resolution_.back().image_weight > 0) image_views_.push_back(v);
  }
  field_ = std::make_unique<FurField>(context, field, prior, root_box(data.roots), options.seed);
  if (options.warm_start) {
    const std::vector<float> z = lifted_strand_latent(prior, options.lying_angle_deg);
    field_->start_at(z, 0.5413f, 0.1f);  // softplus(0.5413) = 1: every segment starts fully confident
  }
  impl_ = std::make_unique<Impl>(context, data, *field_, options_);
  std::int32_t regions = 0;
  for (std::int32_t r : data.roots.region) regions = std::max(regions, r + 1);
  length_raw_.assign(std::size_t(regions), length_factor_raw(1.0, options_.length_bounds));
  length_m_.assign(length_raw_.size(), 0.0), length_v_.assign(length_raw_.size(), 0.0);
  apply_length_factors();
  start_ = state();
  nn::AdamConfig adam;
  const std::uint64_t count = field_->mlp().parameters().size();
  impl_->adam = std::make_unique<nn::Adam>(context, count, adam, std::vector<nn::ParamGroup>{{0, count, 1.f, options.weight_decay}});
  if (options.train_decoder) {
    const std::uint64_t dc = prior.decoder().parameters().size();
    impl_->adam_decoder = std::make_unique<nn::Adam>(context, dc, adam, std::vector<nn::ParamGroup>{{0, dc, 0.1f, 0.f}});
  }
}

FurTrainer::~FurTrainer() = default;

double FurTrainer::strand_width(std::uint32_t strands) const {
  if (options_.strand_width > 0 || !(data_.fur_area > 0)) return (options_.strand_width > 0 ? options_.strand_width : 0.0025) * data_.scene_radius;
  return options_.coverage * data_.fur_area / (2.0 * std::max(1u, strands) * mean_root_length_);
}

std::uint32_t FurTrainer::batch() const { return impl_->batch.strands; }

FurStepReport FurTrainer::train_step() {
  Impl& m = *impl_;
  const Stopwatch t_step;
  FurStepReport r;
  r.warm = step_ < options_.warm_steps || data_.train.empty();
  const std::uint64_t seed = splitmix64(splitmix64(options_.seed) ^ step_);
  const std::vector<std::uint32_t> ids = sample_indices(data_.roots.size(), m.batch.strands, seed);
  std::vector<float> normalised, frames, guides(ids.size() * 3), lengths(ids.size());
  strand_inputs(data_.roots, ids, field_->box(), normalised, frames, field_->length_factors());
  for (std::size_t k = 0; k < ids.size(); ++k) {
    for (int a = 0; a < 3; ++a) guides[3 * k + std::size_t(a)] = data_.roots.direction[ids[k]][a];
    lengths[k] = frames[k * kFrameFloats + 3];  // the knowledge's length x the region's factor
  }
  m.batch.roots.upload(normalised);
  m.batch.frames.upload(frames);
  m.guides.upload(guides);
  m.lengths.upload(lengths);
  json passes = json::object();
  passes["inputs"] = t_step.seconds();

  gpu::Stream stream(context_);
  Stopwatch t;
  field_->forward(stream, m.batch);
  stream.submit_and_wait();
  passes["field_forward"] = t.seconds();

  const splat::StrandShape shape{m.batch.strands, kStrandPoints};
  const double radius = data_.scene_radius;
  const FurView* view = nullptr;
  FurView patch;      // the step's native-resolution patch (with patches)
  double weight = 0;  // the view's image weight
  if (!r.warm && !image_views_.empty()) {
    std::mt19937_64 rng(seed ^ 0x5bd1e995ull);
    r.view = image_views_[std::uniform_int_distribution<std::size_t>(0, image_views_.size() - 1)(rng)];
    weight = resolution_[r.view].image_weight;
    t.restart();
    if (data_.patches) {
      patch = data_.patches->cut(r.view, data_.patches->place(r.view, rng()));
      view = &patch;
      m.upload_view(patch), m.uploaded_view = ~0u;
      passes["patch"] = t.seconds();
      t.restart();
    } else {
      view = &data_.train[r.view];
      if (m.uploaded_view != r.view) m.upload_view(*view), m.uploaded_view = r.view;
    }
    const std::uint64_t px = view->pixels();
    const auto [near, far] = depth_range(*view, double(*std::max_element(lengths.begin(), lengths.end())));
    splat::RasterParams params;
    params.gaussian.width = strand_width(m.batch.strands);
    m.rasterizer.forward(shape, m.batch.points, m.batch.confidence, splat::raster_camera(view->crop, near, far), params,
                         m.depth->range(0, px), m.image->range(0, 5 * px));
    passes["raster_forward"] = t.seconds();
    r.view = view->camera, r.image = true;

    t.restart();
    const splat::ImageSize size{view->crop.width, view->crop.height};
    const splat::ImageLossInputBuffers in{m.image->range(0, px), m.image->range(px, 2 * px), m.image->range(3 * px, px)};
    const splat::ImageLossTargetBuffers targets{m.mask->range(0, px), m.weight->range(0, px), m.angle->range(0, px),
                                                m.confidence->range(0, px)};
    stream.fill(m.grad_image->range(4 * px, px), 0u);  // no loss on the depth channel
    const splat::ImageLossGradientBuffers grads{m.grad_image->range(0, px), m.grad_image->range(px, 2 * px), m.grad_image->range(3 * px, px)};
    splat::image_losses_forward(stream, size, {}, in, targets, m.losses);
    splat::image_losses_backward(stream, size, {}, in, targets, m.losses, float(weight * options_.weights.silhouette),
                                 float(weight * options_.weights.orientation * view->orientation_reliability), grads);
    m.rasterizer.backward(stream, m.grad_image->range(0, 5 * px), m.batch.grad_points, m.batch.grad_confidence, false);
    stream.submit_and_wait();
    passes["image_losses_and_raster_backward"] = t.seconds();
  } else {
    stream.fill(m.batch.grad_confidence, 0u);
  }

  t.restart();
  StrandLossBatch lb{m.loss_shape, m.grid, m.batch.points, m.guides, m.lengths, m.sdf};
  StrandLossWeights w{options_.weights.direction, r.warm ? 0.0 : options_.weights.curvature, options_.weights.penetration / radius};
  strand_losses_forward(stream, lb, m.loss_scratch);
  // Onto the rasteriser's gradient when the image losses ran; else it starts the points' gradient.
  strand_losses_backward(stream, lb, m.loss_scratch, w, m.batch.grad_points, view != nullptr);
  const bool chamfer = !r.warm && m.chamfer_queries > 0 && options_.weights.chamfer > 0;
  if (chamfer) {
    std::vector<float> q(m.chamfer_queries * 3);
    const std::vector<std::uint32_t> qi = sample_indices(data_.surface_points.size() / 3, std::uint32_t(m.chamfer_queries), seed ^ 0xc4a3ull);
    for (std::size_t k = 0; k < qi.size(); ++k)
      for (int a = 0; a < 3; ++a) q[3 * k + std::size_t(a)] = data_.surface_points[3 * std::size_t(qi[k]) + std::size_t(a)];
    m.queries.upload(q);
    strand_chamfer_forward(stream, m.chamfer_grid, m.queries, m.batch.points, m.chamfer_scratch);
    strand_chamfer_backward(stream, m.queries, m.batch.points, m.chamfer_scratch, options_.weights.chamfer / (radius * radius),
                            m.batch.grad_points, true);
  }
  const bool envelope = !r.warm && m.has_envelope && options_.weights.envelope > 0;
  if (envelope) {
    const StrandLossBatch eb{m.loss_shape, m.envelope_grid, m.batch.points, m.guides, m.lengths, m.envelope_sdf};
    strand_losses_forward(stream, eb, m.envelope_scratch);
    strand_losses_backward(stream, eb, m.envelope_scratch, {0.0, 0.0, options_.weights.envelope / radius}, m.batch.grad_points, true);
  }
  stream.submit_and_wait();
  passes["strand_losses"] = t.seconds();

  t.restart();
  field_->backward(stream, m.batch);
  nn::LearningRateSchedule schedule{options_.lr, 0, options_.steps, options_.lr_floor};
  r.lr = schedule.at(step_);
  if (!r.warm && options_.image_ramp_steps > 0)  // !warm: step_ >= warm_steps
    r.lr *= std::min(1.f, float(step_ - options_.warm_steps + 1) / float(options_.image_ramp_steps));
  m.adam->step(stream, field_->mlp().parameters(), field_->mlp().gradients(), r.lr);
  if (m.adam_decoder) m.adam_decoder->step(stream, field_->prior().decoder().parameters(), field_->prior().decoder().gradients(), r.lr);
  stream.submit_and_wait();
  passes["field_backward_and_adam"] = t.seconds();
  // The lengths learn from the losses that see them: the image losses and the chamfer to M_NeuS.
  r.length_factor_mean = last_.length_factor_mean;  // the factors change only where they learn
  if (!r.warm && options_.length_lr > 0 && !length_raw_.empty())
    r.length_factor_mean = learn_lengths(ids, float(options_.length_lr * r.lr / options_.lr));

  // The losses of this step (without the loss weights; the image losses with the view's image
  // weight and reliability, as they enter the loss), the optimiser's counters.
  t.restart();
  const std::array<double, 3> geo = strand_loss_values(m.loss_scratch, m.loss_shape);
  r.direction = geo[0], r.curvature = geo[1], r.penetration = geo[2];
  if (view) {
    const std::vector<float> l = m.losses.download();
    r.silhouette = weight * l[0], r.orientation = weight * l[1] * view->orientation_reliability;  // as they enter the loss
  }
  if (chamfer) {
    const ChamferValue cv = strand_chamfer_value(m.chamfer_scratch);
    r.chamfer = cv.loss, r.chamfer_unmatched = cv.unmatched;
  }
  if (envelope) r.envelope = strand_loss_values(m.envelope_scratch, m.loss_shape)[2];
  const FurLossWeights& fw = options_.weights;
  r.loss = fw.direction * r.direction + fw.penetration * r.penetration / radius +
           (r.warm ? 0.0 : fw.curvature * r.curvature + fw.silhouette * r.silhouette + fw.orientation * r.orientation +
                               fw.chamfer * r.chamfer / (radius * radius) + fw.envelope * r.envelope / radius);
  const nn::Adam::Counters counters = m.adam->counters();
  r.grad_norm = counters.last_norm;
  r.skipped_steps = counters.skipped;
  passes["readback"] = t.seconds();
  ++step_;
  seconds_ += t_step.seconds();
  r.step = step_;
  r.seconds = seconds_;
  r.pass_seconds = passes;
  return r;
}

double FurTrainer::learn_lengths(const std::vector<std::uint32_t>& ids, float lr) {
  const std::vector<float> grad_frames = impl_->batch.grad_frames.download(0, std::uint64_t(ids.size()) * kFrameFloats);
  std::vector<std::int32_t> region(ids.size());
  std::vector<float> base(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) region[k] = data_.roots.region[ids[k]], base[k] = data_.roots.length[ids[k]];
  const std::vector<double> g = length_factor_gradients<float>(region, base, grad_frames, length_raw_.size());
  // Adam on the raw factors (a handful of numbers: on the host). Each moves about lr a step.
  constexpr double b1 = 0.9, b2 = 0.999, eps = 1e-12;
  ++length_steps_;
  const double c1 = 1 - std::pow(b1, length_steps_), c2 = 1 - std::pow(b2, length_steps_);
  for (std::size_t r = 0; r < length_raw_.size(); ++r) {
    const double gr = g[r] * length_factor_derivative(length_raw_[r], options_.length_bounds);
    if (!std::isfinite(gr)) continue;  // a non-finite step is skipped, as the field's Adam does
    length_m_[r] = b1 * length_m_[r] + (1 - b1) * gr;
    length_v_[r] = b2 * length_v_[r] + (1 - b2) * gr * gr;
    length_raw_[r] -= lr * (length_m_[r] / c1) / (std::sqrt(length_v_[r] / c2) + eps);
  }
  apply_length_factors();
  // The factors' geometric mean over the batch's strands, from its count per region.
  std::vector<std::size_t> count(length_raw_.size(), 0);
  for (std::int32_t r : region)
    if (r >= 0 && std::size_t(r) < count.size()) ++count[std::size_t(r)];
  double log_sum = 0;
  for (std::size_t r = 0; r < count.size(); ++r) log_sum += double(count[r]) * std::log(double(field_->length_factors()[r]));
  return std::exp(log_sum / double(std::max<std::size_t>(1, ids.size())));
}

void FurTrainer::apply_length_factors() {
  LengthFactors f(length_raw_.size());
  for (std::size_t r = 0; r < f.size(); ++r) f[r] = float(length_factor_of(length_raw_[r], options_.length_bounds));
  field_->set_length_factors(std::move(f));
}

FurFieldState FurTrainer::state() const { return {field_->parameters(), field_->length_factors(), step_}; }

void FurTrainer::set_state(const FurFieldState& state) {
  field_->set_parameters(state.parameters);
  field_->set_length_factors(state.length_factors);
}

FurStepReport FurTrainer::train(std::uint32_t until, const std::filesystem::path& checkpoint,
                                const std::function<bool(const FurStepReport&)>& after_step) {
  until = std::min(until, options_.steps);
  FurStepReport report = last_;
  if (!warm_ && step_ == options_.warm_steps) warm_ = state();
  while (step_ < until) {
    report = train_step();
    last_ = report;
    if (step_ == options_.warm_steps) warm_ = state();
    if (step_ % kHistoryEvery == 0 || step_ == until || step_ == options_.warm_steps) history_.push_back(report);
    if (!checkpoint.empty() && nn::checkpoint_due(step_, until, options_.checkpoint_interval)) save_checkpoint(checkpoint);
    if (after_step && !after_step(report)) break;
  }
  return report;
}

std::vector<float> FurTrainer::render(const FurView& view, std::uint32_t strands, unsigned seed) {
  const std::vector<std::uint32_t> ids = sample_indices(data_.roots.size(), strands, seed);
  FurField::Batch batch(*field_, std::uint32_t(ids.size()));
  std::vector<float> normalised, frames;
  strand_inputs(data_.roots, ids, field_->box(), normalised, frames, field_->length_factors());
  batch.roots.upload(normalised);
  batch.frames.upload(frames);
  gpu::Stream stream(context_);
  field_->forward(stream, batch);
  stream.submit_and_wait();
  float longest = 0;
  for (std::size_t k = 0; k < ids.size(); ++k) longest = std::max(longest, frames[k * kFrameFloats + 3]);
  return rasterize(view, batch.points, batch.confidence, std::uint32_t(ids.size()), longest);
}

std::vector<float> FurTrainer::render_strands(const FurView& view, const std::vector<float>& points) {
  const std::size_t per_strand = std::size_t(kStrandPoints) * 3;
  if (points.empty() || points.size() % per_strand) throw InputError("fur: strands to render need " + std::to_string(kStrandPoints) + " points each");
  const std::uint32_t n = std::uint32_t(points.size() / per_strand);
  double reach = 0;  // how far a strand reaches from its root, for the depth range
  for (std::size_t i = 0; i < n; ++i) {
    const float* root = &points[i * per_strand];
    for (std::size_t k = 1; k < kStrandPoints; ++k) {
      const float* q = root + 3 * k;
      reach = std::max(reach, std::hypot(double(q[0] - root[0]), double(q[1] - root[1]), double(q[2] - root[2])));
    }
  }
  gpu::Buffer<float> d_points(context_, points, "fur rendered strands");
  // Fully confident segments: what the warm start renders and what a given groom means.
  gpu::Buffer<float> d_confidence(context_, std::vector<float>(std::size_t(n) * kStrandSegments, 1.f), "fur rendered confidence");
  return rasterize(view, d_points, d_confidence, n, reach);
}

std::vector<float> FurTrainer::rasterize(const FurView& view, gpu::BufferRange points, gpu::BufferRange confidence, std::uint32_t strands,
                                         double reach) {
  const auto [near, far] = depth_range(view, reach);
  splat::RasterParams params;
  params.gaussian.width = strand_width(strands);
  const std::uint64_t px = view.pixels();
  gpu::Buffer<float> depth(context_, view.body_depth, "fur score depth"), image(context_, 5 * px, "fur score image");
  impl_->rasterizer.forward({strands, kStrandPoints}, points, confidence, splat::raster_camera(view.crop, near, far), params, depth, image);
  return image.download();
}

ViewScore score_view(const FurView& view, const std::vector<float>& img) {
  const std::uint64_t px = view.pixels();
  ViewScore s;
  double inter = 0, uni = 0, err = 0, wsum = 0;
  for (std::uint64_t p = 0; p < px; ++p) {
    if (view.silhouette_weight[p] > 0.5f) {
      const bool a = img[p] > 0.5f, m = view.mask[p] > 0.5f;
      inter += a && m, uni += a || m;
    }
    const double ox = img[px + p], oy = img[2 * px + p], w = double(view.gabor_confidence[p]) * view.orientation_weight[p];
    if (w > 0 && std::hypot(ox, oy) > 1e-6) {
      const double beta = 0.5 * std::atan2(oy, ox);
      double d = std::fmod(std::abs(beta - view.gabor_angle[p]), M_PI);
      d = std::min(d, M_PI - d);
      err += w * d, wsum += w;
    }
  }
  s.silhouette_iou = uni > 0 ? inter / uni : 0;
  s.orientation_error_deg = wsum > 0 ? err / wsum * 180.0 / M_PI : 0;
  s.pixels = px;
  return s;
}

namespace {
nn::CheckpointIdentity checkpoint_identity(const FurFieldConfig& field, const FurTrainingOptions& options) {
  return {"fur checkpoint", kCheckpointVersion, field.to_json(), to_json(options)};
}
}  // namespace

void FurTrainer::save_checkpoint(const std::filesystem::path& path) const {
  json history = json::array();
  for (const FurStepReport& r : history_) history.push_back(to_json(r));
  nn::WeightsFile file = nn::checkpoint_file(checkpoint_identity(field_config_, options_), {step_, seconds_, to_json(last_), std::move(history)});
  std::vector<float> p = field_->parameters();
  file.tensors.push_back({"field", {p.size()}, std::move(p)});
  nn::add_state_tensors(impl_->adam->save_state(), "adam.field", file);
  file.config["length_steps"] = length_steps_;
  for (auto [name, values] : {std::pair{"length.raw", &length_raw_}, {"length.m", &length_m_}, {"length.v", &length_v_}})
    file.tensors.push_back({name, {values->size()}, std::vector<float>(values->begin(), values->end())});
  if (warm_) {
    file.config["warm_step"] = warm_->step;
    file.tensors.push_back({"warm.field", {warm_->parameters.size()}, warm_->parameters});
    file.tensors.push_back({"warm.length_factors", {warm_->length_factors.size()}, warm_->length_factors});
  }
  if (impl_->adam_decoder) {
    std::vector<float> d = field_->prior().decoder().parameters().download();
    file.tensors.push_back({"decoder", {d.size()}, std::move(d)});
    nn::add_state_tensors(impl_->adam_decoder->save_state(), "adam.decoder", file);
  }
  nn::save_weights(path, file);
}

namespace {
FurStepReport report_from_json(const json& j) {
  FurStepReport r;
  r.step = j.at("step").get<std::uint32_t>();
  r.warm = j.at("warm").get<bool>();
  r.image = j.contains("view");
  r.view = j.value("view", 0u);
  for (auto [name, field] : {std::pair{"loss", &r.loss}, {"silhouette", &r.silhouette}, {"orientation", &r.orientation},
                             {"direction", &r.direction}, {"chamfer", &r.chamfer}, {"penetration", &r.penetration},
                             {"curvature", &r.curvature}, {"seconds", &r.seconds}})
    *field = j.at(name).get<double>();
  r.envelope = j.value("envelope", 0.0);  // checkpoints before the envelope loss
  r.chamfer_unmatched = j.at("chamfer_unmatched").get<std::uint64_t>();
  r.length_factor_mean = j.value("length_factor_mean", 1.0);
  r.lr = j.at("lr").get<float>();
  r.grad_norm = j.at("grad_norm").get<float>();
  r.skipped_steps = j.at("skipped_steps").get<std::uint32_t>();
  if (j.contains("pass_seconds")) r.pass_seconds = j["pass_seconds"];
  return r;
}
}  // namespace

FurCheckpointState parse_fur_checkpoint(const nn::WeightsFile& file, const std::filesystem::path& path, bool with_decoder) {
  FurCheckpointState s;
  s.field = file.tensor("field", path).values;
  s.field_adam = nn::state_from_tensors(file, "adam.field", path);
  if (with_decoder) s.decoder = file.tensor("decoder", path).values, s.decoder_adam = nn::state_from_tensors(file, "adam.decoder", path);
  s.length_raw = file.tensor("length.raw", path).values;
  s.length_m = file.tensor("length.m", path).values;
  s.length_v = file.tensor("length.v", path).values;
  const nn::CheckpointProgress progress = nn::checkpoint_progress(file, path);
  s.step = progress.step, s.seconds = progress.seconds;
  try {
    const json& c = file.config;
    s.last = report_from_json(progress.last);
    for (const json& r : progress.history) s.history.push_back(report_from_json(r));
    s.length_steps = c.at("length_steps").get<std::uint32_t>();
    if (c.contains("warm_step"))
      s.warm = FurFieldState{file.tensor("warm.field", path).values, file.tensor("warm.length_factors", path).values, c.at("warm_step").get<std::uint32_t>()};
  } catch (const json::exception& e) {
    throw InputError(path.string() + ": " + e.what());
  }
  return s;
}

bool FurTrainer::load_checkpoint(const std::filesystem::path& path) {
  const std::optional<nn::WeightsFile> file = nn::load_checkpoint_of(path, checkpoint_identity(field_config_, options_));
  if (!file) return false;
  FurCheckpointState s = parse_fur_checkpoint(*file, path, impl_->adam_decoder != nullptr);
  if (s.field.size() != field_->mlp().parameters().size())
    throw InputError(path.string() + ": the field has " + std::to_string(s.field.size()) + " parameters, this network " +
                     std::to_string(field_->mlp().parameters().size()));
  if (impl_->adam_decoder && s.decoder.size() != field_->prior().decoder().parameters().size())
    throw InputError(path.string() + ": the decoder's size differs");
  field_->set_parameters(s.field);
  impl_->adam->load_state(s.field_adam);
  if (impl_->adam_decoder) {
    field_->prior().decoder().parameters().upload(s.decoder);
    impl_->adam_decoder->load_state(s.decoder_adam);
  }
  if (s.length_raw.size() != length_raw_.size() || s.length_m.size() != length_raw_.size() || s.length_v.size() != length_raw_.size())
    throw InputError(path.string() + ": the length factors are for " + std::to_string(s.length_raw.size()) + " regions, the roots have " +
                     std::to_string(length_raw_.size()));
  if (s.warm && s.warm->parameters.size() != field_->mlp().parameters().size())
    throw InputError(path.string() + ": the warm-up's field has " + std::to_string(s.warm->parameters.size()) + " parameters, this network " +
                     std::to_string(field_->mlp().parameters().size()));
  length_raw_.assign(s.length_raw.begin(), s.length_raw.end());
  length_m_.assign(s.length_m.begin(), s.length_m.end());
  length_v_.assign(s.length_v.begin(), s.length_v.end());
  length_steps_ = s.length_steps;
  apply_length_factors();
  warm_ = std::move(s.warm);
  step_ = s.step, seconds_ = s.seconds, last_ = s.last, history_ = std::move(s.history);
  return true;
}

}  // namespace nf::fur
