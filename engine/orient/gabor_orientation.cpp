#include "engine/orient/gabor_orientation.hpp"

#include <algorithm>

#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::orient {
namespace {

struct Push {
  std::uint32_t width, rows, row_first, out_rows, has_mask;
  float bin, inv_distance2_sum;
};

constexpr std::uint32_t kTile = 16;  // 16 x 16 output pixels per workgroup

// Pixels per invocation. GPUs: one (256 invocations, small private arrays, broadcast weights).
// CPU devices: weight loads, not FMAs, bound the kernel, so each loaded weight should serve several
// pixels; but the pipeline's compile time grows steeply with them, as LLVM allocates registers for
// PIXELS x taps pair sums. Lavapipe 22.3, 256 x 256 on one thread, uniform weights:
//   1 pixel 476 ms (compile 0.7 s), 2: 282 ms (1.5 s), 4: 186 ms (5.3 s), 16 (storage): minutes.
std::uint32_t invocation_pixels(const gpu::Context& context, std::uint32_t requested) {
  std::uint32_t pixels = requested ? requested : context.info().is_cpu() ? 4 : 1;
  while (kTile * kTile / pixels > context.info().limits.max_workgroup_invocations) pixels *= 2;
  return pixels;
}

std::uint32_t taps4(const GaborBank& bank) { return std::uint32_t((bank.taps.size() + 3) / 4); }

// Tap k sits at dy * span + dx in the shared tile; padding taps point at the centre and weigh 0.
std::vector<std::int32_t> tile_offsets(const GaborBank& bank) {
  const int span = int(kTile) + 2 * bank.radius;
  std::vector<std::int32_t> offsets(taps4(bank) * 4, 0);
  for (std::size_t k = 0; k < bank.taps.size(); ++k) offsets[k] = bank.taps[k].dy * span + bank.taps[k].dx;
  return offsets;
}

// [orientation][taps4 * 4]; the centre weight is halved because the kernel sums it as a pair
// (x2 and /2 are exact in binary floating point).
std::vector<float> packed_weights(const GaborBank& bank) {
  const std::size_t row = taps4(bank) * 4;
  std::vector<float> w(bank.orientations * row, 0.f);
  for (std::uint32_t o = 0; o < bank.orientations; ++o)
    for (std::size_t k = 0; k < bank.taps.size(); ++k)
      w[o * row + k] = float(bank.weight(o, k)) * (k == 0 ? 0.5f : 1.f);
  return w;
}

}  // namespace

GaborOrientationKernel::GaborOrientationKernel(gpu::Context& context, const GaborBank& bank,
                                               std::uint32_t pixels_per_invocation)
    : context_(&context),
      pixels_(invocation_pixels(context, pixels_per_invocation)),
      apron_(std::uint32_t(bank.radius)),
      taps4_(taps4(bank)),
      orientations_(bank.orientations),
      uniform_weights_(std::uint64_t(taps4(bank)) * 16 * bank.orientations <=
                       context.info().limits.max_uniform_buffer_range),
      bin_(float(kPi / bank.orientations)),
      inv_distance2_sum_(float(1.0 / bank.distance2_sum)),
      offsets_(context, tile_offsets(bank), "Gabor tap offsets"),
      weights_(context, packed_weights(bank), "Gabor weights") {
  const std::uint64_t span = kTile + 2 * apron_;
  if (span * span * 4 > context.info().limits.max_compute_shared_memory)
    throw DeviceError("Gabor kernel: a tile of " + std::to_string(span) + "^2 floats exceeds the device's " +
                      std::to_string(context.info().limits.max_compute_shared_memory) + " bytes of shared memory");
}

void GaborOrientationKernel::record(gpu::Stream& stream, const Band& band, gpu::BufferRange dog,
                                    gpu::BufferRange mask, gpu::BufferRange orientation,
                                    gpu::BufferRange confidence) const {
  NF_CHECK(band.row_first + band.out_rows <= band.rows, "Gabor band outputs rows outside its input");
  const std::uint64_t out_pixels = std::uint64_t(band.width) * band.out_rows;
  gpu::require_bytes(dog, std::uint64_t(band.width) * band.rows * 4, "Gabor input (DoG)");
  gpu::require_bytes(orientation, out_pixels * 4, "orientation map");
  gpu::require_bytes(confidence, out_pixels * 4, "confidence map");
  const bool has_mask = mask.size > 0;
  if (has_mask) gpu::require_bytes(mask, (out_pixels + 3) / 4 * 4, "orientation mask");
  const gpu::Kernel& kernel = context_->kernel(
      uniform_weights_ ? "orient/gabor_orientation:ubo" : "orient/gabor_orientation:ssbo",
      {{0, kTile * kTile / pixels_}, {1, kTile}, {2, apron_}, {3, taps4_}, {4, orientations_}, {5, pixels_}});
  const Push push{band.width, band.rows, band.row_first, band.out_rows, has_mask ? 1u : 0u, bin_, inv_distance2_sum_};
  // Storage bindings first, then the uniform one: the order the kernel's reflected layout lists.
  stream.dispatch_groups(kernel, {dog, offsets_, mask, orientation, confidence, weights_}, push,
                         gpu::Elements((band.width + kTile - 1) / kTile, (band.out_rows + kTile - 1) / kTile));
}

}  // namespace nf::orient
