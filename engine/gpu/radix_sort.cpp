#include "engine/gpu/radix_sort.hpp"

#include <bit>

#include "engine/gpu/chunking.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/gpu/scan.hpp"

namespace nf::gpu {
namespace {

struct HistogramPush {
  std::uint32_t n, shift, blocks;
};
struct ScatterPush {
  std::uint32_t n, shift, blocks, has_values;
};

constexpr std::uint32_t kBins = 16, kDigitBits = 4;

}  // namespace

std::uint32_t key_bits_for(std::uint32_t max_key) { return std::max(1, int(std::bit_width(max_key))); }

void radix_sort(Stream& stream, BufferRange keys, BufferRange values, std::uint32_t key_bits) {
  Context& context = stream.context();
  const std::uint64_t n = keys.size / 4;
  if (key_bits < 1 || key_bits > 32) throw InternalError("radix_sort: key_bits must be 1..32");
  if (values.size && values.size != keys.size) throw InternalError("radix_sort: keys and values differ in count");
  if (n > max_binding_elements(context, 4))
    throw DeviceLimitError("radix_sort: " + std::to_string(n) + " keys exceed one binding on '" + context.info().name +
                      "' (maxStorageBufferRange " + std::to_string(context.info().limits.max_storage_buffer_range) +
                      " bytes); sort in parts or use a device with a larger range");
  if (n <= 1) return;

  const std::uint32_t wg = primitive_workgroup(context, 128);
  const std::uint32_t items = context.tuning().items_per_thread;
  const std::vector<SpecConstant> spec{{0, wg}, {1, items}};
  const Kernel& histogram = context.kernel("gpu/radix_histogram", spec);
  const Kernel& scatter = context.kernel("gpu/radix_scatter", spec);
  const std::uint64_t block = std::uint64_t(wg) * items;
  const std::uint32_t blocks = std::uint32_t((n + block - 1) / block);
  const bool has_values = values.size != 0;

  const BufferRange hist = stream.scratch(std::uint64_t(kBins) * blocks * 4, "radix histogram");
  BufferRange alt_keys = stream.scratch(n * 4, "radix keys");
  BufferRange alt_values = has_values ? stream.scratch(n * 4, "radix values") : BufferRange{};
  BufferRange src_keys = keys, src_values = values;
  const std::uint32_t passes = (key_bits + kDigitBits - 1) / kDigitBits;
  const Elements grid(std::uint64_t(blocks) * wg);
  for (std::uint32_t p = 0; p < passes; ++p) {
    const std::uint32_t shift = p * kDigitBits;
    stream.dispatch(histogram, {src_keys, hist}, HistogramPush{std::uint32_t(n), shift, blocks}, grid);
    exclusive_scan(stream, hist, hist);
    stream.dispatch(scatter, {src_keys, src_values, hist, alt_keys, alt_values},
                    ScatterPush{std::uint32_t(n), shift, blocks, has_values ? 1u : 0u}, grid);
    std::swap(src_keys, alt_keys);
    std::swap(src_values, alt_values);
  }
  if (passes % 2) {  // the result sits in the scratch buffers
    stream.copy(src_keys, keys);
    if (has_values) stream.copy(src_values, values);
  }
}

}  // namespace nf::gpu
