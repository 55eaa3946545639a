#pragma once
// GPU key-value radix sort, least significant digit first, 4 bits a pass, stable. Only the low
// `key_bits` bits are sorted (a 20-bit key costs 5 passes, not 8). Reduce-then-scan per pass: block
// histograms, one exclusive scan, stable scatter; no workgroup ever waits on another.
#include <cstdint>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::gpu {

// Records an in-place sort of `keys` (uint32) and, if non-empty, `values` (uint32, same count) by
// the low `key_bits` bits (1..32) of the keys. Rejects arrays larger than one binding.
void radix_sort(Stream& stream, BufferRange keys, BufferRange values, std::uint32_t key_bits = 32);

// Bits needed to represent `max_key` (at least 1).
std::uint32_t key_bits_for(std::uint32_t max_key);

}  // namespace nf::gpu
