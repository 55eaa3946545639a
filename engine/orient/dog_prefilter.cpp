#include "engine/orient/dog_prefilter.hpp"

#include <algorithm>

#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::orient {
namespace {

struct Push {
  std::uint32_t width, rows, low_radius, high_radius, has_high;
};
constexpr std::uint32_t kWorkgroup = 128;

std::vector<float> both_taps(const GaborParams& p) {
  std::vector<float> taps;
  for (const double t : gaussian_half_taps(p.dog_low_sigma)) taps.push_back(float(t));
  if (p.dog_high_sigma > 0)
    for (const double t : gaussian_half_taps(p.dog_high_sigma)) taps.push_back(float(t));
  return taps;
}

}  // namespace

DogPrefilter::DogPrefilter(gpu::Context& context, const GaborParams& params)
    : low_radius_(std::uint32_t(gaussian_half_taps(params.dog_low_sigma).size() - 1)),
      high_radius_(std::uint32_t(gaussian_half_taps(params.dog_high_sigma).size() - 1)),
      has_high_(params.dog_high_sigma > 0),
      taps_(context, both_taps(params), "DoG taps") {}

void DogPrefilter::record(gpu::Stream& stream, std::uint32_t width, std::uint32_t rows, gpu::BufferRange grey,
                          gpu::BufferRange low, gpu::BufferRange high, gpu::BufferRange dog) const {
  const std::uint64_t bytes = std::uint64_t(width) * rows * 4;
  gpu::require_bytes(grey, bytes, "DoG input");
  gpu::require_bytes(low, bytes, "DoG low-pass");
  gpu::require_bytes(dog, bytes, "DoG output");
  if (has_high_) gpu::require_bytes(high, bytes, "DoG high-pass");
  // An unused binding is given as an empty range (the stream binds a dummy).
  const gpu::BufferRange high_used = has_high_ ? gpu::BufferRange{high.buffer, high.offset, bytes} : gpu::BufferRange{};
  const gpu::BufferRange band_low{low.buffer, low.offset, bytes};
  gpu::Context& context = stream.context();
  const Push push{width, rows, low_radius_, high_radius_, has_high_ ? 1u : 0u};
  const gpu::Elements pixels(std::uint64_t(width) * rows);
  stream.dispatch(context.kernel("orient/dog_prefilter:rows", {{0, kWorkgroup}}),
                  {taps_, {grey.buffer, grey.offset, bytes}, band_low, high_used}, push, pixels);
  stream.dispatch(context.kernel("orient/dog_prefilter:columns", {{0, kWorkgroup}}),
                  {taps_, band_low, high_used, {dog.buffer, dog.offset, bytes}}, push, pixels);
}

}  // namespace nf::orient
