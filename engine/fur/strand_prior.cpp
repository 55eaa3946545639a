#include "engine/fur/strand_prior.hpp"

#include <cmath>

#include "engine/core/error.hpp"
#include "engine/gpu/context.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/nn/weights_io.hpp"

namespace nf::fur {
namespace {

constexpr int kFormat = 1;

nn::MlpConfig mlp(std::uint32_t in, const std::vector<std::uint32_t>& hidden, std::uint32_t out) {
  nn::MlpConfig c;
  c.input_dim = in, c.hidden = hidden, c.output_dim = out;
  c.hidden_activation = {nn::Activation::ReLU};
  c.output_activation = {nn::Activation::None};
  return c;
}

std::vector<std::uint32_t> widths(const io::JsonField& f) {
  std::vector<std::uint32_t> w;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const double v = f.at(i).number();
    if (!(v >= 1 && v <= nn::kMaxWidth && v == std::floor(v))) f.at(i).fail("expected a width in 1.." + std::to_string(nn::kMaxWidth));
    w.push_back(std::uint32_t(v));
  }
  return w;
}

// Tensors of one network under a prefix ("encoder.", "decoder.") and back.
void add_tensors(nn::WeightsFile& out, const nn::WeightsFile& net, const std::string& prefix) {
  for (nn::NamedTensor t : net.tensors) {
    t.name = prefix + t.name;
    out.tensors.push_back(std::move(t));
  }
}
nn::WeightsFile tensors_of(const nn::WeightsFile& all, const std::string& prefix, const nn::MlpConfig& config) {
  nn::WeightsFile w;
  w.config = {{"kind", "mlp"}, {"mlp", nn::to_json(config)}};
  for (const nn::NamedTensor& t : all.tensors)
    if (t.name.rfind(prefix, 0) == 0) w.tensors.push_back({t.name.substr(prefix.size()), t.shape, t.values});
  return w;
}

std::unique_ptr<StrandPrior> from_weights(gpu::Context& context, const nn::WeightsFile& w, const std::string& source) {
  if (w.config.value("kind", std::string()) != "strand_prior")
    throw InputError(source + ": not a strand prior (config.kind is " + w.config.value("kind", json("missing")).dump() + ")");
  const StrandPriorConfig config = StrandPriorConfig::from_json(w.config.value("prior", json()), source);
  auto prior = std::make_unique<StrandPrior>(context, config);
  prior->encoder().parameters().upload(nn::mlp_parameters(config.encoder(), tensors_of(w, "encoder.", config.encoder()), source + " (encoder)"));
  prior->decoder().parameters().upload(nn::mlp_parameters(config.decoder(), tensors_of(w, "decoder.", config.decoder()), source + " (decoder)"));
  prior->record = w.config.value("record", json::object());
  return prior;
}

}  // namespace

nn::MlpConfig StrandPriorConfig::encoder() const { return mlp(kStrandValues, encoder_hidden, latent); }
nn::MlpConfig StrandPriorConfig::decoder() const { return mlp(latent, decoder_hidden, kStrandValues); }

json StrandPriorConfig::to_json() const {
  return {{"format", kFormat}, {"latent", latent}, {"encoder_hidden", encoder_hidden}, {"decoder_hidden", decoder_hidden},
          {"points", kStrandPoints}};
}

StrandPriorConfig StrandPriorConfig::from_json(const json& j, const std::string& source) {
  const io::JsonField f(j, source, "config.prior");
  if (!j.is_object()) f.fail("missing or not an object");
  if (f.at("format").number() != kFormat) f.at("format").fail("unsupported format (this build reads " + std::to_string(kFormat) + ")");
  if (f.at("points").number() != kStrandPoints) f.at("points").fail("expected " + std::to_string(kStrandPoints) + " points per strand");
  StrandPriorConfig c;
  const double latent = f.at("latent").number();
  if (!(latent >= 1 && latent <= 1024 && latent == std::floor(latent))) f.at("latent").fail("expected 1..1024");
  c.latent = std::uint32_t(latent);
  c.encoder_hidden = widths(f.at("encoder_hidden"));
  c.decoder_hidden = widths(f.at("decoder_hidden"));
  return c;
}

StrandPrior::StrandPrior(gpu::Context& context, const StrandPriorConfig& config)
    : context_(context),
      config_(config),
      encoder_(std::make_unique<nn::Mlp>(context, config.encoder(), "strand encoder")),
      decoder_(std::make_unique<nn::Mlp>(context, config.decoder(), "strand decoder")) {}

std::vector<float> StrandPrior::encode(const std::vector<float>& strands) {
  const std::uint32_t n = std::uint32_t(strands.size() / (3 * kStrandPoints));
  const std::uint32_t in = encoder_->input_stride(), out = encoder_->output_stride();
  gpu::Buffer<float> input(context_, std::span<const float>(encoder_rows(strands, in)), "strands to encode");
  gpu::Buffer<float> output(context_, std::uint64_t(out) * n, "latents");
  gpu::Stream s(context_);
  encoder_->infer(s, input, output, n);
  s.submit_and_wait();
  const std::vector<float> rows = output.download();
  std::vector<float> latents(std::size_t(n) * config_.latent);
  for (std::uint32_t k = 0; k < n; ++k)
    std::copy_n(rows.begin() + std::ptrdiff_t(std::size_t(k) * out), config_.latent, latents.begin() + std::ptrdiff_t(std::size_t(k) * config_.latent));
  return latents;
}

std::vector<float> StrandPrior::decode(const std::vector<float>& latents) {
  const std::uint32_t n = std::uint32_t(latents.size() / config_.latent);
  const std::uint32_t in = decoder_->input_stride(), out = decoder_->output_stride();
  std::vector<float> rows(std::size_t(in) * n, 0.0f);
  for (std::uint32_t k = 0; k < n; ++k)
    std::copy_n(latents.begin() + std::ptrdiff_t(std::size_t(k) * config_.latent), config_.latent, rows.begin() + std::ptrdiff_t(std::size_t(k) * in));
  gpu::Buffer<float> input(context_, std::span<const float>(rows), "latents to decode");
  gpu::Buffer<float> output(context_, std::uint64_t(out) * n, "decoded segments");
  gpu::Stream s(context_);
  decoder_->infer(s, input, output, n);
  s.submit_and_wait();
  return strands_from_rows(output.download(), out, n);
}

void StrandPrior::save(const std::filesystem::path& path) const {
  nn::WeightsFile w;
  w.config = {{"kind", "strand_prior"}, {"prior", config_.to_json()}, {"record", record}};
  add_tensors(w, nn::mlp_weights(config_.encoder(), encoder_->parameters().download()), "encoder.");
  add_tensors(w, nn::mlp_weights(config_.decoder(), decoder_->parameters().download()), "decoder.");
  nn::save_weights(path, w);
}

std::unique_ptr<StrandPrior> StrandPrior::load(gpu::Context& context, const std::filesystem::path& path) {
  return from_weights(context, nn::load_weights(path), path.string());
}

std::unique_ptr<StrandPrior> StrandPrior::from_bytes(gpu::Context& context, const std::string& bytes, const std::string& source) {
  return from_weights(context, nn::parse_weights(bytes, source), source);
}

std::unique_ptr<StrandPrior> shipped_strand_prior(gpu::Context& context) {
  if (shipped_strand_prior_bytes().empty())
    throw InputError("this build has no strand prior: assets/strand_prior/strand_prior.nfwt was missing when it was built "
                     "(tools/nf prior makes it)");
  return StrandPrior::from_bytes(context, shipped_strand_prior_bytes(), "the shipped strand prior (assets/strand_prior)");
}

std::vector<float> encoder_rows(const std::vector<float>& strands, std::uint32_t stride) {
  const std::size_t n = strands.size() / (3 * kStrandPoints);
  std::vector<float> rows(n * stride, 0.0f);
  for (std::size_t k = 0; k < n; ++k)
    std::copy_n(strands.begin() + std::ptrdiff_t(k * kStrandPoints * 3 + 3), kStrandValues, rows.begin() + std::ptrdiff_t(k * stride));
  return rows;
}

std::vector<float> strands_from_rows(const std::vector<float>& rows, std::uint32_t stride, std::uint32_t count) {
  std::vector<float> strands(std::size_t(count) * kStrandPoints * 3, 0.0f);
  for (std::uint32_t k = 0; k < count; ++k) {
    const float* d = &rows[std::size_t(k) * stride];
    float* p = &strands[std::size_t(k) * kStrandPoints * 3];
    for (std::uint32_t i = 0; i < kStrandSegments; ++i)
      for (int c = 0; c < 3; ++c) p[3 * (i + 1) + c] = p[3 * i + c] + d[3 * i + c] / float(kStrandSegments);
  }
  return strands;
}

std::vector<float> rows_gradient(const std::vector<float>& grad_points, std::uint32_t stride, std::uint32_t count) {
  std::vector<float> grad(std::size_t(count) * stride, 0.0f);
  for (std::uint32_t k = 0; k < count; ++k) {
    const float* gp = &grad_points[std::size_t(k) * kStrandPoints * 3];
    float* g = &grad[std::size_t(k) * stride];
    float suffix[3] = {0, 0, 0};  // sum of dL/dp over the points after segment i
    for (std::uint32_t i = kStrandSegments; i-- > 0;) {
      for (int c = 0; c < 3; ++c) {
        suffix[c] += gp[3 * (i + 1) + c];
        g[3 * i + c] = suffix[c] / float(kStrandSegments);
      }
    }
  }
  return grad;
}

}  // namespace nf::fur
