#include "engine/neus/volume_render.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::neus {
namespace {

struct Push {
  std::uint32_t rays, samples;
  float inv_s, anneal;
};

std::uint64_t rays_per_chunk(const gpu::Context& context, VolumeRenderShape shape, const VolumeRenderParams& params) {
  const std::uint64_t s = shape.samples;
  const std::uint64_t most = gpu::items_per_chunk(context, {s * 4, s * 12, 12, 4});
  // 32-bit indices in the shaders: rgb of a chunk must stay below 2^32 floats.
  const std::uint64_t index_cap = std::max<std::uint64_t>(1, (std::uint64_t(1) << 31) / (s * 3));
  std::uint64_t chunk = std::min(most, index_cap);
  if (params.chunk_rays) chunk = std::min(chunk, params.chunk_rays);
  return std::max<std::uint64_t>(1, chunk);
}

void require_shape(VolumeRenderShape shape, const VolumeRenderInputBuffers& in) {
  if (shape.samples == 0) throw InputError("volume render: samples per ray must be > 0");
  const std::uint64_t n = shape.rays * shape.samples;
  gpu::require_bytes(in.sdf, n * 4, "volume render sdf");
  gpu::require_bytes(in.cos, n * 4, "volume render cos");
  gpu::require_bytes(in.dist, n * 4, "volume render dist");
  gpu::require_bytes(in.rgb, n * 12, "volume render rgb");
}

std::uint64_t check_host(std::uint32_t samples, const VolumeRenderInputs<float>& in) {
  if (samples == 0) throw InputError("volume render: samples per ray must be > 0");
  if (in.sdf.size() % samples)
    throw InputError("volume render: sdf has " + std::to_string(in.sdf.size()) + " floats, not a multiple of " +
                     std::to_string(samples) + " samples per ray");
  const std::uint64_t rays = in.sdf.size() / samples, n = in.sdf.size();
  const auto check = [&](std::span<const float> v, std::uint64_t want, const char* name) {
    if (v.size() != want)
      throw InputError(std::string("volume render: ") + name + " has " + std::to_string(v.size()) + " floats, " +
                       std::to_string(want) + " expected for " + std::to_string(rays) + " rays x " +
                       std::to_string(samples) + " samples");
    require_finite(v, name);
  };
  check(in.sdf, n, "sdf");
  check(in.cos, n, "cos");
  check(in.dist, n, "dist");
  check(in.rgb, 3 * n, "rgb");
  return rays;
}

struct DeviceInputs {
  gpu::Buffer<float> sdf, cos, dist, rgb;
  DeviceInputs(gpu::Context& c, const VolumeRenderInputs<float>& in)
      : sdf(c, in.sdf, "sdf"), cos(c, in.cos, "cos"), dist(c, in.dist, "dist"), rgb(c, in.rgb, "rgb") {}
  VolumeRenderInputBuffers buffers() const { return {sdf, cos, dist, rgb}; }
};

}  // namespace

void validate(const VolumeRenderParams& params) {
  if (!(params.inv_s > 0.f) || !std::isfinite(params.inv_s))
    throw InputError("volume render: inv_s must be a positive finite number, got " + std::to_string(params.inv_s));
  if (!(params.cos_anneal >= 0.f && params.cos_anneal <= 1.f))
    throw InputError("volume render: cos_anneal must be in [0, 1], got " + std::to_string(params.cos_anneal));
}

void volume_render_forward(gpu::Stream& stream, VolumeRenderShape shape, const VolumeRenderParams& params,
                           const VolumeRenderInputBuffers& in, const VolumeRenderOutputBuffers& out) {
  validate(params);
  require_shape(shape, in);
  gpu::require_bytes(out.colour, shape.rays * 12, "volume render colour");
  gpu::require_bytes(out.opacity, shape.rays * 4, "volume render opacity");
  gpu::Context& context = stream.context();
  const std::uint32_t wg = gpu::primitive_workgroup(context, 64);
  const gpu::Kernel& kernel = context.kernel("neus/volume_render_fwd", {{0, wg}});
  const std::uint64_t s = shape.samples, chunk = rays_per_chunk(context, shape, params);
  for (std::uint64_t first = 0; first < shape.rays; first += chunk) {
    const std::uint64_t count = std::min(chunk, shape.rays - first);
    stream.dispatch(kernel,
                    {gpu::sub_range(in.sdf, s * 4, first, count), gpu::sub_range(in.cos, s * 4, first, count),
                     gpu::sub_range(in.dist, s * 4, first, count), gpu::sub_range(in.rgb, s * 12, first, count),
                     gpu::sub_range(out.colour, 12, first, count), gpu::sub_range(out.opacity, 4, first, count)},
                    Push{std::uint32_t(count), shape.samples, params.inv_s, params.cos_anneal},
                    gpu::Elements(count));
  }
}

void volume_render_backward(gpu::Stream& stream, VolumeRenderShape shape, const VolumeRenderParams& params,
                            const VolumeRenderInputBuffers& in, gpu::BufferRange grad_colour,
                            gpu::BufferRange grad_opacity, const VolumeRenderGradientBuffers& grads) {
  validate(params);
  require_shape(shape, in);
  const std::uint64_t s = shape.samples, n = shape.rays * s;
  gpu::require_bytes(grad_colour, shape.rays * 12, "volume render grad colour");
  gpu::require_bytes(grad_opacity, shape.rays * 4, "volume render grad opacity");
  gpu::require_bytes(grads.sdf, n * 4, "volume render grad sdf");
  gpu::require_bytes(grads.cos, n * 4, "volume render grad cos");
  gpu::require_bytes(grads.rgb, n * 12, "volume render grad rgb");
  gpu::require_bytes(grads.inv_s, 4, "volume render grad inv_s");
  gpu::Context& context = stream.context();
  const gpu::BufferRange inv_s = gpu::sub_range(grads.inv_s, 4, 0, 1);
  stream.fill(inv_s, 0u);
  const std::uint32_t wg = gpu::primitive_workgroup(context, 64);
  const gpu::Kernel& kernel = context.kernel("neus/volume_render_bwd", {{0, wg}});
  const std::uint64_t chunk = rays_per_chunk(context, shape, params);
  for (std::uint64_t first = 0; first < shape.rays; first += chunk) {
    const std::uint64_t count = std::min(chunk, shape.rays - first);
    stream.dispatch(kernel,
                    {gpu::sub_range(in.sdf, s * 4, first, count), gpu::sub_range(in.cos, s * 4, first, count),
                     gpu::sub_range(in.dist, s * 4, first, count), gpu::sub_range(in.rgb, s * 12, first, count),
                     gpu::sub_range(grad_colour, 12, first, count), gpu::sub_range(grad_opacity, 4, first, count),
                     gpu::sub_range(grads.sdf, s * 4, first, count), gpu::sub_range(grads.cos, s * 4, first, count),
                     gpu::sub_range(grads.rgb, s * 12, first, count), inv_s},
                    Push{std::uint32_t(count), shape.samples, params.inv_s, params.cos_anneal},
                    gpu::Elements(count));
  }
}

VolumeRenderOutputs<float> volume_render(gpu::Context& context, std::uint32_t samples,
                                         const VolumeRenderInputs<float>& inputs, const VolumeRenderParams& params) {
  const VolumeRenderParams p{inputs.inv_s, params.cos_anneal, params.chunk_rays};
  validate(p);
  const std::uint64_t rays = check_host(samples, inputs);
  if (rays == 0) return {};
  const DeviceInputs dev(context, inputs);
  gpu::Buffer<float> colour(context, rays * 3, "colour"), opacity(context, rays, "opacity");
  gpu::Stream stream(context);
  volume_render_forward(stream, {rays, samples}, p, dev.buffers(), {colour, opacity});
  stream.submit_and_wait();
  return {colour.download(), opacity.download()};
}

VolumeRenderResult volume_render_with_gradients(gpu::Context& context, std::uint32_t samples,
                                                const VolumeRenderInputs<float>& inputs,
                                                const VolumeRenderParams& params, std::span<const float> grad_colour,
                                                std::span<const float> grad_opacity) {
  const VolumeRenderParams p{inputs.inv_s, params.cos_anneal, params.chunk_rays};
  validate(p);
  const std::uint64_t rays = check_host(samples, inputs);
  const auto check = [&](std::span<const float> v, std::uint64_t want, const char* name) {
    if (v.size() != want)
      throw InputError(std::string("volume render: ") + name + " has " + std::to_string(v.size()) + " floats, " +
                       std::to_string(want) + " expected");
    require_finite(v, name);
  };
  check(grad_colour, rays * 3, "grad_colour");
  check(grad_opacity, rays, "grad_opacity");
  if (rays == 0) return {};
  const std::uint64_t n = rays * samples;
  const DeviceInputs dev(context, inputs);
  gpu::Buffer<float> colour(context, rays * 3, "colour"), opacity(context, rays, "opacity");
  gpu::Buffer<float> gcol(context, grad_colour, "grad colour"), gop(context, grad_opacity, "grad opacity");
  gpu::Buffer<float> gsdf(context, n, "grad sdf"), gcos(context, n, "grad cos"), grgb(context, n * 3, "grad rgb"),
      ginv(context, 1, "grad inv_s");
  gpu::Stream stream(context);
  volume_render_forward(stream, {rays, samples}, p, dev.buffers(), {colour, opacity});
  volume_render_backward(stream, {rays, samples}, p, dev.buffers(), gcol, gop, {gsdf, gcos, grgb, ginv});
  stream.submit_and_wait();
  return {{colour.download(), opacity.download()}, {gsdf.download(), gcos.download(), grgb.download(), ginv.download()[0]}};
}

}  // namespace nf::neus
