#pragma once
// GPU stream compaction: keep the elements whose flag is non-zero, in order.
#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::gpu {

// Records out[j] = i for the j-th i with flags[i] != 0 (or values[i] when `values` is given);
// count (one element) gets the number kept. `out` must hold as many elements as `flags`.
// Rejects arrays larger than one binding (maxStorageBufferRange) with a DeviceError.
void compact(Stream& stream, BufferRange flags, BufferRange out, BufferRange count, BufferRange values = {});

}  // namespace nf::gpu
