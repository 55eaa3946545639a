#include "engine/neus/neus_field.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/error.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/nn/init.hpp"

namespace nf::neus {
namespace {

constexpr std::uint32_t kWorkgroup = 64;
constexpr std::uint32_t kInferenceChunk = 1u << 16;  // points per inference dispatch group
constexpr float kSoftplusBeta = 100.f;               // NeuS's SDF activation

struct PointsPush {
  std::uint32_t n, in_stride, write_position;
  float h, point_scale, point_offset;
};
struct CombinePush {
  std::uint32_t n, samples_per_ray, out_stride, features, cin_stride;
  float h;
};
struct CombineBackwardPush {
  std::uint32_t n, samples_per_ray, out_stride, features, cin_stride;
  float h, eikonal_weight;
  std::uint32_t has_colour;
};
struct ColourPush {
  std::uint32_t n, out_stride, backward;
};

std::uint64_t groups_of(std::uint64_t n) { return std::max<std::uint64_t>(1, (n + kWorkgroup - 1) / kWorkgroup); }

}  // namespace

nn::MlpConfig NeusFieldConfig::sdf_mlp() const {
  nn::MlpConfig c;
  c.input_dim = encoding == FieldEncoding::HashGrid ? 3 + hash.output_dim() : frequency.output_dim();
  c.hidden = sdf_hidden;
  c.output_dim = 1 + features;
  c.hidden_activation = {nn::Activation::Softplus, kSoftplusBeta};
  c.output_activation = {nn::Activation::None};
  return c;
}

nn::MlpConfig NeusFieldConfig::colour_mlp() const {
  nn::MlpConfig c;
  c.input_dim = colour_input_dim();
  c.hidden = colour_hidden;
  c.output_dim = 3;
  c.hidden_activation = {nn::Activation::ReLU};
  c.output_activation = {nn::Activation::None};  // sigmoid in field_colour.comp
  return c;
}

void NeusFieldConfig::validate() const {
  if (encoding == FieldEncoding::Frequency && (frequency.dims != 3 || !frequency.include_input))
    throw InputError("neus field: the frequency encoding must take 3 dims and include the input");
  if (encoding == FieldEncoding::HashGrid) nn::HashGrid check(hash);
  if (!(init_radius > 0.f && init_radius < 1.f)) throw InputError("neus field: init_radius must lie in (0, 1)");
  sdf_mlp().validate();
  colour_mlp().validate();
}

json to_json(const NeusFieldConfig& c) {
  json j;
  j["encoding"] = c.encoding == FieldEncoding::HashGrid ? "hash_grid" : "frequency";
  j["hash_grid"] = {{"levels", c.hash.levels},
                    {"features", c.hash.features},
                    {"log2_table", c.hash.log2_table},
                    {"base_resolution", c.hash.base_resolution},
                    {"max_resolution", c.hash.max_resolution}};
  j["frequencies"] = c.frequency.frequencies;
  j["sdf_hidden"] = c.sdf_hidden;
  j["features"] = c.features;
  j["colour_hidden"] = c.colour_hidden;
  j["init_radius"] = c.init_radius;
  return j;
}

NeusField::NeusField(gpu::Context& context, const NeusFieldConfig& config, unsigned seed)
    : context_(context), config_(config) {
  config_.validate();
  if (config_.encoding == FieldEncoding::HashGrid) {
    hash_.emplace(config_.hash);
    table_ = std::make_unique<gpu::Buffer<float>>(context, hash_->initial_table(seed), "neus hash table");
    table_gradient_ = std::make_unique<gpu::Buffer<float>>(context, config_.hash.parameter_count(), "neus hash gradient");
    table_gradient_->fill_u32(0);
  } else {
    frequency_.emplace(config_.frequency);
  }
  sdf_ = std::make_unique<nn::Mlp>(context, config_.sdf_mlp(), "neus sdf");
  colour_ = std::make_unique<nn::Mlp>(context, config_.colour_mlp(), "neus colour");
  nn::InitOptions geometric{nn::InitScheme::Geometric, seed, config_.init_radius, 3};
  sdf_->parameters().upload(nn::initial_parameters(config_.sdf_mlp(), geometric));
  colour_->parameters().upload(nn::initial_parameters(config_.colour_mlp(), {nn::InitScheme::KaimingUniform, seed + 1}));
}

NeusField::Batch::Batch(NeusField& f, std::uint32_t rays_, std::uint32_t samples_per_ray_)
    : rays(rays_),
      samples_per_ray(samples_per_ray_),
      n(rays_ * samples_per_ray_),
      samples(f.context_, std::max(1u, n), "neus samples"),
      dirs(f.context_, std::max(1u, rays_), "neus ray directions"),
      sdf(f.context_, std::max(1u, n), "neus sdf"),
      cos(f.context_, std::max(1u, n), "neus cos"),
      rgb(f.context_, std::max(1u, n) * 3ull, "neus rgb"),
      gradient(f.context_, std::max(1u, n), "neus gradient"),
      eikonal_partials(f.context_, groups_of(n), "neus eikonal partials"),
      encoder_points(f.context_, std::max(1u, n) * 12ull, "neus encoder points"),
      sdf_input(f.context_, std::max(1u, n) * 4ull * f.sdf_->input_stride(), "neus sdf input"),
      sdf_grad_output(f.context_, std::max(1u, n) * 4ull * f.sdf_->output_stride(), "neus sdf output gradient"),
      sdf_grad_input(f.context_, std::max(1u, n) * 4ull * f.sdf_->input_stride(), "neus sdf input gradient"),
      colour_input(f.context_, std::max(1u, n) * std::uint64_t(f.colour_->input_stride()), "neus colour input"),
      colour_grad_output(f.context_, std::max(1u, n) * std::uint64_t(f.colour_->output_stride()), "neus colour output gradient"),
      colour_grad_input(f.context_, std::max(1u, n) * std::uint64_t(f.colour_->input_stride()), "neus colour input gradient"),
      sdf_workspace(*f.sdf_, 4 * n),
      colour_workspace(*f.colour_, n) {
  if (rays_ == 0 || samples_per_ray_ == 0) throw InputError("neus batch: rays and samples per ray must be positive");
}

void NeusField::encode(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange rows, std::uint32_t count) const {
  if (hash_)
    hash_->forward(stream, points, table_->whole(), rows, count, {sdf_->input_stride(), 3});
  else
    frequency_->forward(stream, points, rows, count);
}

void NeusField::forward(gpu::Stream& stream, Batch& b, float h) const {
  const std::uint32_t m = 4 * b.n;
  const bool hash = hash_.has_value();
  stream.begin_pass("neus encode");
  stream.dispatch(context_.kernel("neus/field_points", {{0, kWorkgroup}}),
                  {b.samples.whole(), b.encoder_points.whole(), b.sdf_input.whole()},
                  PointsPush{b.n, sdf_->input_stride(), hash ? 1u : 0u, h, hash ? 0.5f : 1.f, hash ? 0.5f : 0.f},
                  gpu::Elements(m));
  encode(stream, b.encoder_points.whole(), b.sdf_input.whole(), m);
  stream.end_pass();
  stream.begin_pass("neus sdf mlp forward");
  sdf_->forward(stream, b.sdf_workspace, b.sdf_input.whole());
  stream.end_pass();
  stream.begin_pass("neus colour forward");
  stream.dispatch(context_.kernel("neus/field_combine_fwd", {{0, kWorkgroup}}),
                  {b.sdf_workspace.output(), b.dirs.whole(), b.colour_input.whole(), b.sdf.whole(), b.cos.whole(),
                   b.gradient.whole(), b.eikonal_partials.whole()},
                  CombinePush{b.n, b.samples_per_ray, sdf_->output_stride(), config_.features, colour_->input_stride(), h},
                  gpu::Elements(groups_of(b.n) * kWorkgroup));
  colour_->forward(stream, b.colour_workspace, b.colour_input.whole());
  stream.dispatch(context_.kernel("neus/field_colour", {{0, kWorkgroup}}),
                  {b.colour_workspace.output(), b.rgb.whole(), b.cos.whole(), b.colour_grad_output.whole()},
                  ColourPush{b.n, colour_->output_stride(), 0}, gpu::Elements(b.n));
  stream.end_pass();
}

void NeusField::backward(gpu::Stream& stream, Batch& b, float h, float eikonal_weight, gpu::BufferRange grad_sdf,
                         gpu::BufferRange grad_cos, gpu::BufferRange grad_rgb) {
  stream.begin_pass("neus colour backward");
  stream.dispatch(context_.kernel("neus/field_colour", {{0, kWorkgroup}}),
                  {b.colour_workspace.output(), b.rgb.whole(), grad_rgb, b.colour_grad_output.whole()},
                  ColourPush{b.n, colour_->output_stride(), 1}, gpu::Elements(b.n));
  colour_->backward(stream, b.colour_workspace, b.colour_input.whole(), b.colour_grad_output.whole(),
                    b.colour_grad_input.whole(), false);
  stream.dispatch(context_.kernel("neus/field_combine_bwd", {{0, kWorkgroup}}),
                  {b.colour_grad_input.whole(), grad_sdf, grad_cos, b.gradient.whole(), b.dirs.whole(),
                   b.sdf_grad_output.whole()},
                  CombineBackwardPush{b.n, b.samples_per_ray, sdf_->output_stride(), config_.features,
                                      colour_->input_stride(), h, eikonal_weight / float(std::max(1u, b.n)), 1u},
                  gpu::Elements(b.n));
  stream.end_pass();
  const bool hash = hash_.has_value();
  stream.begin_pass("neus sdf mlp backward");
  sdf_->backward(stream, b.sdf_workspace, b.sdf_input.whole(), b.sdf_grad_output.whole(),
                 hash ? b.sdf_grad_input.whole() : gpu::BufferRange{}, false);
  stream.end_pass();
  if (hash) {
    gpu::ScopedPass pass(stream, "neus hash backward");
    stream.fill(table_gradient_->whole(), 0);
    hash_->backward(stream, b.encoder_points.whole(), table_->whole(), b.sdf_grad_input.whole(),
                    table_gradient_->whole(), {}, 4 * b.n, false, {sdf_->input_stride(), 3});
  }
}

std::vector<float> NeusField::sdf_at(const std::vector<glm::vec3>& points) const {
  std::vector<float> out(points.size());
  if (points.empty()) return out;
  const std::uint32_t chunk = std::uint32_t(std::min<std::size_t>(kInferenceChunk, points.size()));
  const bool hash = hash_.has_value();
  gpu::Buffer<float> enc(context_, std::uint64_t(chunk) * 3, "neus query encoder points");
  gpu::Buffer<float> rows(context_, std::uint64_t(chunk) * sdf_->input_stride(), "neus query rows");
  gpu::Buffer<float> result(context_, std::uint64_t(chunk) * sdf_->output_stride(), "neus query sdf");
  // The hash path uploads whole rows (raw position in columns 0-2, the encoding writes the rest);
  // the frequency encoding writes every column itself.
  std::vector<float> enc_host(std::size_t(chunk) * 3), row_host(hash ? std::size_t(chunk) * sdf_->input_stride() : 0);
  gpu::Stream stream(context_);
  for (std::size_t first = 0; first < points.size(); first += chunk) {
    const std::uint32_t count = std::uint32_t(std::min<std::size_t>(chunk, points.size() - first));
    for (std::uint32_t i = 0; i < count; ++i)
      for (int a = 0; a < 3; ++a) {
        const float x = points[first + i][a];
        enc_host[3 * i + a] = hash ? x * 0.5f + 0.5f : x;
        if (hash) row_host[std::size_t(i) * sdf_->input_stride() + a] = x;
      }
    enc.upload(std::span<const float>(enc_host.data(), std::size_t(count) * 3));
    if (hash) rows.upload(std::span<const float>(row_host.data(), std::size_t(count) * sdf_->input_stride()));
    encode(stream, enc.whole(), rows.whole(), count);
    sdf_->infer(stream, rows.whole(), result.whole(), count);
    stream.submit_and_wait();
    const std::vector<float> r = result.download(0, std::uint64_t(count) * sdf_->output_stride());
    for (std::uint32_t i = 0; i < count; ++i) out[first + i] = r[std::size_t(i) * sdf_->output_stride()];
  }
  return out;
}

NeusField::Shading NeusField::shade(const std::vector<glm::vec3>& points, const std::vector<glm::vec3>& dirs, float h) {
  if (points.size() != dirs.size()) throw InternalError("neus shade: points and directions differ in count");
  Shading out;
  out.sdf.resize(points.size());
  out.gradient.resize(points.size());
  out.rgb.resize(points.size());
  if (points.empty()) return out;
  const std::uint32_t chunk = std::uint32_t(std::min<std::size_t>(8192, points.size()));
  Batch b(*this, chunk, 1);
  gpu::Stream stream(context_);
  std::vector<glm::vec4> p(chunk), d(chunk);
  for (std::size_t first = 0; first < points.size(); first += chunk) {
    const std::size_t count = std::min<std::size_t>(chunk, points.size() - first);
    for (std::size_t i = 0; i < chunk; ++i) {
      const std::size_t k = first + std::min(i, count - 1);  // pad with the last point
      p[i] = glm::vec4(points[k], 0.f);
      d[i] = glm::vec4(dirs[k], 0.f);
    }
    b.samples.upload(p);
    b.dirs.upload(d);
    forward(stream, b, h);
    stream.submit_and_wait();
    const std::vector<float> sdf = b.sdf.download(), rgb = b.rgb.download();
    const std::vector<glm::vec4> g = b.gradient.download();
    for (std::size_t i = 0; i < count; ++i) {
      out.sdf[first + i] = sdf[i];
      out.gradient[first + i] = glm::vec3(g[i]);
      out.rgb[first + i] = {rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]};
    }
  }
  return out;
}

std::vector<std::pair<std::string, std::vector<float>>> NeusField::save_parameters() const {
  std::vector<std::pair<std::string, std::vector<float>>> t;
  if (table_) t.emplace_back("hash_table", table_->download());
  t.emplace_back("sdf", sdf_->parameters().download());
  t.emplace_back("colour", colour_->parameters().download());
  return t;
}

void NeusField::load_parameters(const std::vector<std::pair<std::string, std::vector<float>>>& tensors) {
  const auto find = [&](const std::string& name, std::uint64_t count) -> const std::vector<float>& {
    for (const auto& [n, v] : tensors)
      if (n == name) {
        if (v.size() != count)
          throw InputError("neus model: tensor '" + name + "' holds " + std::to_string(v.size()) + " values, the " +
                           "configured network needs " + std::to_string(count));
        return v;
      }
    throw InputError("neus model: tensor '" + name + "' is missing");
  };
  if (table_) table_->upload(find("hash_table", table_->size()));
  sdf_->parameters().upload(find("sdf", sdf_->parameters().size()));
  colour_->parameters().upload(find("colour", colour_->parameters().size()));
}

}  // namespace nf::neus
