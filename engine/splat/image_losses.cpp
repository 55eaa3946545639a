#include "engine/splat/image_losses.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::splat {
namespace {

struct PixelsPush {
  std::uint32_t n, per_group, out_offset;
  float tau_floor, omin2;
  std::uint32_t shift[8];
};
struct FinishPush {
  std::uint32_t n;
  float norm_floor;
  std::uint32_t losses_shift;
};
struct BackwardPush {
  std::uint32_t n;
  float tau_floor, omin2, grad_silhouette, grad_orientation;
  std::uint32_t shift[12];
};

constexpr std::uint32_t kMaxGroups = 1024;  // partials per chunk of the forward

std::uint64_t storage_alignment(const gpu::Context& context) {
  return std::max<std::uint64_t>(4, context.info().limits.min_storage_buffer_offset_alignment);
}

// Pixels per chunk: a plane's chunk, plus the shift below, fits one binding (fewer when the caller
// asks, so that tests exercise the chunked path on small images).
std::uint64_t pixels_per_chunk(const gpu::Context& context, const ImageLossParams& params) {
  const std::uint64_t most = gpu::max_binding_elements(context, 4) - storage_alignment(context) / 4;
  return params.chunk_pixels ? std::min(params.chunk_pixels, most) : most;
}

// Floats [first, first + count) of `r` as a binding that starts on the device's offset alignment,
// and the shift (in floats) where the data begins inside it. Lets planes of a larger image bind at
// any pixel count; the few floats before the data are bound but never touched.
struct Bound {
  gpu::BufferRange range;
  std::uint32_t shift;
};
Bound bind(const gpu::Context& context, gpu::BufferRange r, std::uint64_t first, std::uint64_t count) {
  if (r.offset % 4) throw InternalError("image losses: a buffer range starts off a float boundary");
  const std::uint64_t align = storage_alignment(context);
  const std::uint64_t start = r.offset + first * 4, base = start / align * align;
  return {{r.buffer, base, start - base + count * 4}, std::uint32_t((start - base) / 4)};
}

void require_sizes(ImageSize size, const ImageLossInputBuffers& in, const ImageLossTargetBuffers& tg) {
  const std::uint64_t n = size.pixels();
  gpu::require_bytes(in.alpha, n * 4, "image loss alpha");
  gpu::require_bytes(in.orientation, n * 8, "image loss orientation (x and y planes)");
  gpu::require_bytes(in.tau, n * 4, "image loss tau");
  gpu::require_bytes(tg.mask, n * 4, "image loss mask");
  gpu::require_bytes(tg.weight, n * 4, "image loss weight");
  gpu::require_bytes(tg.gabor_angle, n * 4, "image loss gabor_angle");
  gpu::require_bytes(tg.gabor_confidence, n * 4, "image loss gabor_confidence");
}

void require_positive(double value, const char* name) {
  if (!(value > 0) || !std::isfinite(value))
    throw InputError(std::string("image losses: ") + name + " must be a positive finite number, got " +
                     std::to_string(value));
}

void check_host(ImageSize size, const ImageLossInputs<float>& in, const ImageLossTargets<float>& tg) {
  const std::uint64_t n = size.pixels();
  const auto check = [&](std::span<const float> v, std::uint64_t want, const char* name) {
    if (v.size() != want)
      throw InputError(std::string("image losses: ") + name + " has " + std::to_string(v.size()) + " floats, " +
                       std::to_string(want) + " expected for " + std::to_string(size.width) + "x" +
                       std::to_string(size.height) + " pixels");
    require_finite(v, name);
  };
  check(in.alpha, n, "alpha");
  check(in.orientation, 2 * n, "orientation");
  check(in.tau, n, "tau");
  check(tg.mask, n, "mask");
  check(tg.weight, n, "weight");
  check(tg.gabor_angle, n, "gabor_angle");
  check(tg.gabor_confidence, n, "gabor_confidence");
  const auto non_negative = [](std::span<const float> v, const char* name) {
    const auto it = std::find_if(v.begin(), v.end(), [](float x) { return x < 0.f; });
    if (it != v.end())
      throw InputError(std::string("image losses: ") + name + ": element " + std::to_string(it - v.begin()) + " is " +
                       std::to_string(*it) + "; must be >= 0");
  };
  non_negative(tg.weight, "weight");
  non_negative(tg.gabor_confidence, "gabor_confidence");
}

// Device copies of a view's arrays (non-empty images only).
struct DeviceView {
  gpu::Buffer<float> alpha, orientation, tau, mask, weight, angle, confidence;
  DeviceView(gpu::Context& c, const ImageLossInputs<float>& in, const ImageLossTargets<float>& tg)
      : alpha(c, in.alpha, "alpha"), orientation(c, in.orientation, "orientation"), tau(c, in.tau, "tau"),
        mask(c, tg.mask, "mask"), weight(c, tg.weight, "weight"), angle(c, tg.gabor_angle, "gabor_angle"),
        confidence(c, tg.gabor_confidence, "gabor_confidence") {}
  ImageLossInputBuffers inputs() const { return {alpha, orientation, tau}; }
  ImageLossTargetBuffers targets() const { return {mask, weight, angle, confidence}; }
};

ImageLossValues<float> values_of(const std::vector<float>& v) { return {v[0], v[1], v[2], v[3]}; }

}  // namespace

void validate(const ImageLossParams& params) {
  require_positive(params.tau_floor, "tau_floor");
  require_positive(params.orientation_min, "orientation_min");
  require_positive(params.norm_floor, "norm_floor");
}

void image_losses_forward(gpu::Stream& stream, ImageSize size, const ImageLossParams& params,
                          const ImageLossInputBuffers& in, const ImageLossTargetBuffers& tg, gpu::BufferRange losses) {
  validate(params);
  require_sizes(size, in, tg);
  gpu::require_bytes(losses, 16, "image losses output");
  gpu::Context& context = stream.context();
  const std::uint32_t wg = gpu::primitive_workgroup(context, 256);
  const gpu::Kernel& pixels = context.kernel("splat/image_losses_fwd:pixels", {{0, wg}});
  const gpu::Kernel& finish = context.kernel("splat/image_losses_fwd:finish", {{0, wg}});
  const std::uint64_t n = size.pixels(), chunk = pixels_per_chunk(context, params);
  const std::uint64_t chunks = (n + chunk - 1) / chunk;
  const std::uint64_t per_thread = std::uint64_t(context.tuning().items_per_thread) * 4;
  const float omin = float(params.orientation_min);
  gpu::BufferRange partials{};
  if (chunks > 0) partials = stream.scratch(chunks * kMaxGroups * 16, "image loss partials");
  std::uint32_t slots = 0;
  for (std::uint64_t first = 0; first < n; first += chunk) {
    const std::uint64_t count = std::min(chunk, n - first);
    const std::uint32_t groups =
        std::uint32_t(std::clamp<std::uint64_t>((count + wg * per_thread - 1) / (wg * per_thread), 1, kMaxGroups));
    const Bound b[8] = {bind(context, in.alpha, first, count),        bind(context, in.orientation, first, count),
                        bind(context, in.orientation, n + first, count), bind(context, in.tau, first, count),
                        bind(context, tg.mask, first, count),            bind(context, tg.weight, first, count),
                        bind(context, tg.gabor_angle, first, count),     bind(context, tg.gabor_confidence, first, count)};
    PixelsPush push{std::uint32_t(count), std::uint32_t((count + groups - 1) / groups), slots,
                    float(params.tau_floor), omin * omin, {}};
    for (int k = 0; k < 8; ++k) push.shift[k] = b[k].shift;
    stream.dispatch_groups(pixels,
                           {b[0].range, b[1].range, b[2].range, b[3].range, b[4].range, b[5].range, b[6].range,
                            b[7].range, partials},  // the kernel writes partials [slots, slots + groups)
                           push, gpu::Elements(groups));
    slots += groups;
  }
  // An empty image binds no partials (an unused binding): the finish pass writes 0 losses.
  const gpu::BufferRange used = slots ? gpu::sub_range(partials, 16, 0, slots) : gpu::BufferRange{};
  const Bound out = bind(context, losses, 0, 4);
  stream.dispatch_groups(finish, {used, out.range}, FinishPush{slots, float(params.norm_floor), out.shift},
                         gpu::Elements(1));
}

void image_losses_backward(gpu::Stream& stream, ImageSize size, const ImageLossParams& params,
                           const ImageLossInputBuffers& in, const ImageLossTargetBuffers& tg, gpu::BufferRange losses,
                           float grad_silhouette, float grad_orientation, const ImageLossGradientBuffers& grads) {
  validate(params);
  require_sizes(size, in, tg);
  const std::uint64_t n = size.pixels();
  gpu::require_bytes(losses, 16, "image losses (forward output)");
  gpu::require_bytes(grads.alpha, n * 4, "image loss grad alpha");
  gpu::require_bytes(grads.orientation, n * 8, "image loss grad orientation");
  gpu::require_bytes(grads.tau, n * 4, "image loss grad tau");
  if (!std::isfinite(grad_silhouette) || !std::isfinite(grad_orientation))
    throw InputError("image losses: upstream gradients must be finite, got " + std::to_string(grad_silhouette) +
                     " and " + std::to_string(grad_orientation));
  gpu::Context& context = stream.context();
  const std::uint32_t wg = gpu::primitive_workgroup(context, 256);
  const gpu::Kernel& kernel = context.kernel("splat/image_losses_bwd", {{0, wg}});
  const std::uint64_t chunk = pixels_per_chunk(context, params);
  const float omin = float(params.orientation_min);
  for (std::uint64_t first = 0; first < n; first += chunk) {
    const std::uint64_t count = std::min(chunk, n - first);
    const Bound b[12] = {bind(context, in.alpha, first, count),          bind(context, in.orientation, first, count),
                         bind(context, in.orientation, n + first, count),   bind(context, in.tau, first, count),
                         bind(context, tg.mask, first, count),              bind(context, tg.weight, first, count),
                         bind(context, tg.gabor_angle, first, count),       bind(context, tg.gabor_confidence, first, count),
                         bind(context, grads.alpha, first, count),          bind(context, grads.orientation, first, count),
                         bind(context, grads.orientation, n + first, count), bind(context, grads.tau, first, count)};
    BackwardPush push{std::uint32_t(count), float(params.tau_floor), omin * omin, grad_silhouette, grad_orientation, {}};
    for (int k = 0; k < 12; ++k) push.shift[k] = b[k].shift;
    stream.dispatch(kernel,
                    {b[0].range, b[1].range, b[2].range, b[3].range, b[4].range, b[5].range, b[6].range, b[7].range,
                     b[8].range, b[9].range, b[10].range, b[11].range, gpu::sub_range(losses, 4, 0, 4)},
                    push, gpu::Elements(count));
  }
}

ImageLossValues<float> image_losses(gpu::Context& context, ImageSize size, const ImageLossInputs<float>& inputs,
                                    const ImageLossTargets<float>& targets, const ImageLossParams& params) {
  validate(params);
  check_host(size, inputs, targets);
  const float floor = float(params.norm_floor);
  if (size.pixels() == 0) return {0.f, 0.f, floor, floor};
  const DeviceView view(context, inputs, targets);
  gpu::Buffer<float> losses(context, 4, "image losses");
  gpu::Stream stream(context);
  image_losses_forward(stream, size, params, view.inputs(), view.targets(), losses);
  stream.submit_and_wait();
  return values_of(losses.download());
}

ImageLossResult image_losses_with_gradients(gpu::Context& context, ImageSize size,
                                            const ImageLossInputs<float>& inputs,
                                            const ImageLossTargets<float>& targets, float grad_silhouette,
                                            float grad_orientation, const ImageLossParams& params) {
  validate(params);
  check_host(size, inputs, targets);
  const std::uint64_t n = size.pixels();
  const float floor = float(params.norm_floor);
  if (n == 0) return {{0.f, 0.f, floor, floor}, {}};
  const DeviceView view(context, inputs, targets);
  gpu::Buffer<float> losses(context, 4, "image losses");
  gpu::Buffer<float> grad_alpha(context, n, "grad alpha"), grad_orientation_buf(context, 2 * n, "grad orientation"),
      grad_tau(context, n, "grad tau");
  gpu::Stream stream(context);
  image_losses_forward(stream, size, params, view.inputs(), view.targets(), losses);
  image_losses_backward(stream, size, params, view.inputs(), view.targets(), losses, grad_silhouette,
                        grad_orientation, {grad_alpha, grad_orientation_buf, grad_tau});
  stream.submit_and_wait();
  return {values_of(losses.download()), {grad_alpha.download(), grad_orientation_buf.download(), grad_tau.download()}};
}

}  // namespace nf::splat
