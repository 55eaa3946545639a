#pragma once
// Splitting arrays into ranges a kernel binding may cover (maxStorageBufferRange, 128 MiB on
// lavapipe), with every chunk starting on minStorageBufferOffsetAlignment (and on
// minTexelBufferOffsetAlignment, so a chunk may also be bound as a texel buffer).
#include <algorithm>
#include <cstdint>
#include <initializer_list>
#include <numeric>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/context.hpp"

namespace nf::gpu {

// Largest element count one binding may cover, a multiple of the offset alignment.
inline std::uint64_t max_binding_elements(const Context& context, std::uint64_t element_bytes) {
  const DeviceLimits& l = context.info().limits;
  const std::uint64_t align = std::max<std::uint64_t>(l.min_storage_buffer_offset_alignment, element_bytes);
  const std::uint64_t bytes = std::min<std::uint64_t>(l.max_storage_buffer_range, 1ull << 32) / align * align;
  return bytes / element_bytes;
}

// The sub-range of `range` holding elements [first, first + count).
inline BufferRange sub_range(BufferRange range, std::uint64_t element_bytes, std::uint64_t first, std::uint64_t count) {
  return {range.buffer, range.offset + first * element_bytes, count * element_bytes};
}

// Items (strands, rays...) per chunk when each item owns `bytes_per_item` bytes in several arrays:
// every array's chunk fits one storage binding and starts on both the storage and the texel offset
// alignment (callers that bind texel views bound maxTexelBufferElements themselves).
inline std::uint64_t items_per_chunk(const Context& context, std::initializer_list<std::uint64_t> bytes_per_item) {
  const DeviceLimits& l = context.info().limits;
  const std::uint64_t align = std::lcm(std::max<std::uint64_t>(1, l.min_storage_buffer_offset_alignment),
                                       std::max<std::uint64_t>(1, l.min_texel_buffer_offset_alignment));
  const std::uint64_t range = std::min<std::uint64_t>(l.max_storage_buffer_range, 1ull << 32);
  std::uint64_t step = 1, most = ~0ull;
  for (const std::uint64_t b : bytes_per_item) {
    if (b == 0) continue;
    step = std::lcm(step, align / std::gcd(align, b));
    most = std::min(most, range / b);
  }
  if (most < step) throw DeviceError("one item needs more than a storage-buffer binding allows on this device");
  return most / step * step;
}

// Workgroup size for the primitives: a multiple of the subgroup size, as nf_wg_rank() requires.
inline std::uint32_t primitive_workgroup(const Context& context, std::uint32_t preferred) {
  const std::uint32_t subgroup = std::max<std::uint32_t>(1, context.info().limits.subgroup_size);
  const std::uint32_t wg = std::max(preferred, subgroup) / subgroup * subgroup;
  return std::min(wg, context.info().limits.max_workgroup_size[0]);
}

}  // namespace nf::gpu
