#include "engine/fur/fur_field.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/error.hpp"
#include "engine/gpu/context.hpp"
#include "engine/nn/init.hpp"

namespace nf::fur {

nn::MlpConfig FurFieldConfig::mlp(std::uint32_t latent) const {
  nn::MlpConfig c;
  c.input_dim = nn::FrequencyEncodingConfig{3, frequencies, true}.output_dim();
  c.hidden = hidden;
  c.output_dim = latent + 1;  // the latent, then the confidence's raw value
  c.hidden_activation = {nn::Activation::ReLU};
  c.output_activation = {nn::Activation::None};
  return c;
}

json FurFieldConfig::to_json() const { return {{"frequencies", frequencies}, {"hidden", hidden}}; }

glm::vec3 RootBox::normalise(glm::vec3 p) const {
  glm::vec3 out;
  for (int a = 0; a < 3; ++a) {
    const float extent = hi[a] - lo[a];
    out[a] = extent > 0 ? 2.f * (p[a] - lo[a]) / extent - 1.f : 0.f;
  }
  return out;
}

RootBox root_box(const Roots& roots) {
  RootBox box{glm::vec3(0.f), glm::vec3(0.f)};
  if (roots.size() == 0) return box;
  box.lo = box.hi = roots.position[0];
  for (const glm::vec3& p : roots.position) box.lo = glm::min(box.lo, p), box.hi = glm::max(box.hi, p);
  return box;
}

void strand_inputs(const Roots& roots, const std::vector<std::uint32_t>& ids, const RootBox& box, std::vector<float>& normalised,
                   std::vector<float>& frames, const LengthFactors& length_factors) {
  normalised.resize(ids.size() * 3);
  frames.resize(ids.size() * kFrameFloats);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const std::uint32_t r = ids[k];
    const glm::vec3 n = box.normalise(roots.position[r]);
    float* f = &frames[k * kFrameFloats];
    for (int a = 0; a < 3; ++a) {
      normalised[3 * k + std::size_t(a)] = n[a];
      f[a] = roots.position[r][a];
      f[4 + a] = roots.tangent[r][a];
      f[7 + a] = roots.bitangent[r][a];
      f[10 + a] = roots.normal[r][a];
    }
    f[3] = roots.length[r] * length_factor(length_factors, roots.region[r]);
  }
}

FurField::FurField(gpu::Context& context, const FurFieldConfig& config, StrandPrior& prior, const RootBox& box, unsigned seed)
    : context_(context), config_(config), prior_(prior), box_(box), encoding_(nn::FrequencyEncodingConfig{3, config.frequencies, true}) {
  const nn::MlpConfig mlp_config = config.mlp(prior.config().latent);
  mlp_config.validate();
  if (encoding_.config().output_stride() != nn::pad4(mlp_config.input_dim))
    throw InternalError("fur field: the encoding's rows do not match the MLP's input");
  mlp_ = std::make_unique<nn::Mlp>(context, mlp_config, "fur field");
  mlp_->parameters().upload(nn::initial_parameters(mlp_config, {nn::InitScheme::KaimingUniform, seed}));
}

void FurField::start_at(const std::vector<float>& latent, float confidence_raw, float weight_scale) {
  const std::uint32_t L = prior_.config().latent;
  if (latent.size() != L) throw InternalError("fur field: start latent of the wrong size");
  std::vector<float> p = mlp_->parameters().download();
  const nn::LayerShape& last = mlp_->layers().back();
  for (std::uint64_t i = 0; i < std::uint64_t(last.out) * last.in_stride; ++i) p[last.weight_offset + i] *= weight_scale;
  for (std::uint32_t j = 0; j < L; ++j) p[last.bias_offset + j] = latent[j];
  p[last.bias_offset + L] = confidence_raw;
  mlp_->parameters().upload(p);
}

FurHeadShape FurField::head_shape(std::uint32_t strands) const {
  return {strands, prior_.config().latent, mlp_->output_stride(), prior_.decoder().input_stride(), kStrandSegments};
}

StrandGeometryShape FurField::geometry_shape(std::uint32_t strands) const {
  return {strands, kStrandSegments, prior_.decoder().output_stride()};
}

FurField::Batch::Batch(FurField& f, std::uint32_t n)
    : strands(n),
      roots(f.context_, std::uint64_t(n) * 3, "fur roots"),
      frames(f.context_, std::uint64_t(n) * kFrameFloats, "fur frames"),
      encoded(f.context_, std::uint64_t(n) * f.encoding_.config().output_stride(), "fur encoded roots"),
      latents(f.context_, std::uint64_t(n) * f.prior_.decoder().input_stride(), "fur latents"),
      confidence(f.context_, std::uint64_t(n) * kStrandSegments, "fur segment confidence"),
      points(f.context_, std::uint64_t(n) * kStrandPoints * 3, "fur strand points"),
      grad_points(f.context_, std::uint64_t(n) * kStrandPoints * 3, "fur point gradients"),
      grad_confidence(f.context_, std::uint64_t(n) * kStrandSegments, "fur confidence gradients"),
      grad_rows(f.context_, std::uint64_t(n) * f.prior_.decoder().output_stride(), "fur decoder row gradients"),
      grad_frames(f.context_, std::uint64_t(n) * kFrameFloats, "fur frame gradients"),
      grad_latents(f.context_, std::uint64_t(n) * f.prior_.decoder().input_stride(), "fur latent gradients"),
      grad_head(f.context_, std::uint64_t(n) * f.mlp_->output_stride(), "fur head gradients"),
      field(*f.mlp_, n),
      decoder(f.prior_.decoder(), n) {}

void FurField::forward(gpu::Stream& stream, Batch& b) const {
  encoding_.forward(stream, b.roots, b.encoded, b.strands);
  mlp_->forward(stream, b.field, b.encoded);
  fur_head_forward(stream, head_shape(b.strands), b.field.output(), b.latents, b.confidence);
  prior_.decoder().forward(stream, b.decoder, b.latents);
  strand_geometry_forward(stream, geometry_shape(b.strands), b.decoder.output(), b.frames, b.points);
}

void FurField::backward(gpu::Stream& stream, Batch& b) {
  strand_geometry_backward(stream, geometry_shape(b.strands), b.decoder.output(), b.frames, b.grad_points, b.grad_rows, b.grad_frames);
  prior_.decoder().backward(stream, b.decoder, b.latents, b.grad_rows, b.grad_latents, false);
  fur_head_backward(stream, head_shape(b.strands), b.field.output(), b.grad_latents, b.grad_confidence, b.grad_head);
  mlp_->backward(stream, b.field, b.encoded, b.grad_head, {}, false);
}

void FurField::infer(const Roots& roots, const std::vector<std::uint32_t>& ids, std::uint32_t chunk,
                     const std::function<void(std::size_t, std::uint32_t, const std::vector<float>&, const std::vector<float>&)>& sink) {
  chunk = std::max<std::uint32_t>(1, std::min<std::uint64_t>(chunk, std::max<std::size_t>(ids.size(), 1)));
  const std::uint32_t enc_stride = encoding_.config().output_stride(), out_stride = mlp_->output_stride();
  const std::uint32_t lat_stride = prior_.decoder().input_stride(), row_stride = prior_.decoder().output_stride();
  gpu::Buffer<float> d_roots(context_, std::uint64_t(chunk) * 3, "fur inference roots");
  gpu::Buffer<float> d_frames(context_, std::uint64_t(chunk) * kFrameFloats, "fur inference frames");
  gpu::Buffer<float> d_encoded(context_, std::uint64_t(chunk) * enc_stride, "fur inference encoded");
  gpu::Buffer<float> d_rows(context_, std::uint64_t(chunk) * out_stride, "fur inference MLP rows");
  gpu::Buffer<float> d_latents(context_, std::uint64_t(chunk) * lat_stride, "fur inference latents");
  gpu::Buffer<float> d_conf(context_, std::uint64_t(chunk) * kStrandSegments, "fur inference confidence");
  gpu::Buffer<float> d_segments(context_, std::uint64_t(chunk) * row_stride, "fur inference segments");
  gpu::Buffer<float> d_points(context_, std::uint64_t(chunk) * kStrandPoints * 3, "fur inference points");
  std::vector<float> normalised, frames, confidence;
  for (std::size_t first = 0; first < ids.size(); first += chunk) {
    const std::uint32_t n = std::uint32_t(std::min<std::size_t>(chunk, ids.size() - first));
    const std::vector<std::uint32_t> part(ids.begin() + std::ptrdiff_t(first), ids.begin() + std::ptrdiff_t(first + n));
    strand_inputs(roots, part, box_, normalised, frames, length_factors_);
    d_roots.upload(normalised);
    d_frames.upload(frames);
    gpu::Stream s(context_);
    encoding_.forward(s, d_roots, d_encoded, n);
    mlp_->infer(s, d_encoded, d_rows, n);
    fur_head_forward(s, head_shape(n), d_rows, d_latents, d_conf);
    prior_.decoder().infer(s, d_latents, d_segments, n);
    strand_geometry_forward(s, geometry_shape(n), d_segments.range(0, std::uint64_t(n) * row_stride), d_frames.range(0, std::uint64_t(n) * kFrameFloats),
                            d_points);
    s.submit_and_wait();
    const std::vector<float> seg_conf = d_conf.download(0, std::uint64_t(n) * kStrandSegments);
    confidence.resize(n);
    for (std::uint32_t k = 0; k < n; ++k) confidence[k] = seg_conf[std::size_t(k) * kStrandSegments];
    sink(first, n, d_points.download(0, std::uint64_t(n) * kStrandPoints * 3), confidence);
  }
}

std::vector<float> FurField::parameters() const { return mlp_->parameters().download(); }

void FurField::set_parameters(const std::vector<float>& values) {
  if (values.size() != mlp_->parameters().size())
    throw InputError("fur field: " + std::to_string(values.size()) + " parameters given, the network has " +
                     std::to_string(mlp_->parameters().size()));
  mlp_->parameters().upload(values);
}

void FurField::set_length_factors(LengthFactors factors) {
  for (std::size_t r = 0; r < factors.size(); ++r)
    if (!(factors[r] > 0) || !std::isfinite(factors[r]))
      throw InputError("fur field: the length factor of region " + std::to_string(r) + " is " + std::to_string(factors[r]) +
                       "; it must be finite and positive");
  length_factors_ = std::move(factors);
}

}  // namespace nf::fur
