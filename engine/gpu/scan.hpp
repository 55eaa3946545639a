#pragma once
// GPU exclusive prefix sum of uint32 (reduce-then-scan: block sums, a recursive scan of those, then
// each block scanned with its offset; no inter-workgroup waiting). Arrays larger than one binding
// are scanned chunk by chunk with a carry. In-place use (input == output) is allowed.
#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::gpu {

// output[i] = input[0] + ... + input[i-1]; `total` (optional, one element) gets the full sum.
void exclusive_scan(Stream& stream, BufferRange input, BufferRange output, BufferRange total = {});

// As exclusive_scan, counting non-zero elements (input[i] != 0 counts as 1): compaction offsets.
void exclusive_scan_flags(Stream& stream, BufferRange flags, BufferRange output, BufferRange total = {});

}  // namespace nf::gpu
