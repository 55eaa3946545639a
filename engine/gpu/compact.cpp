#include "engine/gpu/compact.hpp"

#include "engine/gpu/chunking.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/gpu/scan.hpp"

namespace nf::gpu {
namespace {
struct ScatterPush {
  std::uint32_t n, has_values;
};
}  // namespace

void compact(Stream& stream, BufferRange flags, BufferRange out, BufferRange count, BufferRange values) {
  Context& context = stream.context();
  const std::uint64_t n = flags.size / 4;
  if (n > max_binding_elements(context, 4))
    throw DeviceLimitError("compact: " + std::to_string(n) + " elements exceed one binding on '" + context.info().name +
                      "' (maxStorageBufferRange " + std::to_string(context.info().limits.max_storage_buffer_range) +
                      " bytes); compact the array in parts");
  if (out.size < flags.size) throw InternalError("compact: output smaller than the flags");
  if (values.size && values.size < flags.size) throw InternalError("compact: values smaller than the flags");
  if (n == 0) {
    stream.fill(sub_range(count, 4, 0, 1), 0);
    return;
  }
  const BufferRange offsets = stream.scratch(n * 4, "compact offsets");
  exclusive_scan_flags(stream, flags, offsets, sub_range(count, 4, 0, 1));
  const Kernel& scatter = context.kernel("gpu/compact_scatter", {{0, primitive_workgroup(context, 256)}});
  stream.dispatch(scatter, {flags, offsets, values, sub_range(out, 4, 0, n)},
                  ScatterPush{std::uint32_t(n), values.size ? 1u : 0u}, Elements(n));
}

}  // namespace nf::gpu
