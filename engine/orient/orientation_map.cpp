#include "engine/orient/orientation_map.hpp"

#include <algorithm>
#include <memory>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/orient/dog_prefilter.hpp"
#include "engine/orient/gabor_orientation.hpp"

namespace nf::orient {
namespace {

void validate_input(const io::Image& image, const std::vector<std::uint8_t>* mask) {
  if (image.width == 0 || image.height == 0) throw InputError("orientation map: the image is empty");
  if (image.channels < 1 || image.channels > 4 ||
      image.pixels.size() != std::size_t(image.width) * image.height * image.channels)
    throw InputError("orientation map: image of " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                     "x" + std::to_string(image.channels) + " holds " + std::to_string(image.pixels.size()) +
                     " values");
  if (mask && mask->size() != std::size_t(image.width) * image.height)
    throw InputError("orientation mask: " + std::to_string(mask->size()) + " values for an image of " +
                     std::to_string(image.width) + "x" + std::to_string(image.height));
  require_finite(image.pixels, "orientation map image");
}

// Mask bytes of rows [y0, y1) packed four to a word, as the kernel reads them.
std::vector<std::uint32_t> pack_mask(const std::vector<std::uint8_t>& mask, std::size_t first, std::size_t count) {
  std::vector<std::uint32_t> words((count + 3) / 4, 0);
  for (std::size_t i = 0; i < count; ++i)
    if (mask[first + i]) words[i / 4] |= 0xffu << (8 * (i % 4));
  return words;
}

}  // namespace

std::vector<float> luminance(const io::Image& image) {
  const std::size_t n = std::size_t(image.width) * image.height;
  std::vector<float> grey(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float* p = &image.pixels[i * image.channels];
    grey[i] = image.channels >= 3 ? 0.2989f * p[0] + 0.5870f * p[1] + 0.1140f * p[2] : p[0];
  }
  return grey;
}

OrientationMap gabor_orientation(gpu::Context& context, const io::Image& image, const std::vector<std::uint8_t>* mask,
                                 const GaborParams& params) {
  validate_input(image, mask);
  const GaborBank bank = make_gabor_bank(params);
  const DogPrefilter dog(context, params);
  const GaborOrientationKernel gabor(context, bank, params.pixels_per_invocation);
  const std::vector<float> grey = luminance(image);
  const std::uint32_t w = image.width, h = image.height;

  // Each band of output rows needs `apron` rows of input either side to match the whole image.
  const std::uint32_t apron = dog.radius() + gabor.radius();
  const std::uint64_t max_rows = gpu::max_binding_elements(context, 4) / w;
  if (max_rows <= 2ull * apron)
    throw InputError("orientation map: image width " + std::to_string(w) + " is too wide for one storage-buffer "
                     "binding of this device");
  std::uint32_t band = std::uint32_t(std::min<std::uint64_t>(max_rows - 2ull * apron, h));
  if (params.band_rows) band = std::min(band, params.band_rows);
  const std::uint32_t in_rows_max = std::min(h, band + 2 * apron);

  const std::uint64_t in_pixels = std::uint64_t(w) * in_rows_max, out_pixels = std::uint64_t(w) * band;
  gpu::Buffer<float> d_grey(context, in_pixels, "orientation grey");
  gpu::Buffer<float> d_low(context, in_pixels, "orientation DoG low");
  gpu::Buffer<float> d_high(context, in_pixels, "orientation DoG high");
  gpu::Buffer<float> d_dog(context, in_pixels, "orientation DoG");
  gpu::Buffer<float> d_orient(context, out_pixels, "orientation map");
  gpu::Buffer<float> d_conf(context, out_pixels, "confidence map");
  std::unique_ptr<gpu::Buffer<std::uint32_t>> d_mask;
  if (mask) d_mask = std::make_unique<gpu::Buffer<std::uint32_t>>(context, (out_pixels + 3) / 4, "orientation mask");

  OrientationMap out;
  out.orientation = {w, h, 1, std::vector<float>(std::size_t(w) * h)};
  out.confidence = {w, h, 1, std::vector<float>(std::size_t(w) * h)};
  gpu::Stream stream(context);
  for (std::uint32_t y0 = 0; y0 < h; y0 += band) {
    const std::uint32_t y1 = std::min(h, y0 + band);
    const std::uint32_t in0 = y0 > apron ? y0 - apron : 0, in1 = std::min(h, y1 + apron);
    const std::uint64_t n_in = std::uint64_t(w) * (in1 - in0), n_out = std::uint64_t(w) * (y1 - y0);
    d_grey.upload(std::span<const float>(grey).subspan(std::size_t(in0) * w, n_in));
    gpu::BufferRange mask_range{};
    if (mask) {
      const std::vector<std::uint32_t> words = pack_mask(*mask, std::size_t(y0) * w, n_out);
      d_mask->upload(words);
      mask_range = d_mask->range(0, words.size());
    }
    {
      gpu::ScopedPass pass(stream, "orient/dog_prefilter");
      dog.record(stream, w, in1 - in0, d_grey.range(0, n_in), d_low.range(0, n_in), d_high.range(0, n_in),
                 d_dog.range(0, n_in));
    }
    {
      gpu::ScopedPass pass(stream, "orient/gabor");
      gabor.record(stream, {w, in1 - in0, y0 - in0, y1 - y0}, d_dog.range(0, n_in), mask_range,
                   d_orient.range(0, n_out), d_conf.range(0, n_out));
    }
    stream.submit_and_wait();
    const std::vector<float> o = d_orient.download(0, n_out), c = d_conf.download(0, n_out);
    std::copy(o.begin(), o.end(), out.orientation.pixels.begin() + std::ptrdiff_t(std::size_t(y0) * w));
    std::copy(c.begin(), c.end(), out.confidence.pixels.begin() + std::ptrdiff_t(std::size_t(y0) * w));
  }
  return out;
}

}  // namespace nf::orient
