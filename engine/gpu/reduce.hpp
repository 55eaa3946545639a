#pragma once
// GPU reduction: sum, min or max of a float, uint or int array. Arrays larger than one binding
// (maxStorageBufferRange) are reduced chunk by chunk. The sum of an empty array is 0; min and max of
// an empty array are the identities (+inf/-inf, UINT_MAX/0, INT_MAX/INT_MIN).
#include <cstdint>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::gpu {

enum class ReduceOp { Sum, Min, Max };
enum class ScalarType { F32, U32, I32 };

// Records the reduction of `input` (whole 4-byte elements) into the first element of `output`.
void reduce(Stream& stream, ReduceOp op, ScalarType type, BufferRange input, BufferRange output);

template <class T> constexpr ScalarType scalar_type_of();
template <> constexpr ScalarType scalar_type_of<float>() { return ScalarType::F32; }
template <> constexpr ScalarType scalar_type_of<std::uint32_t>() { return ScalarType::U32; }
template <> constexpr ScalarType scalar_type_of<std::int32_t>() { return ScalarType::I32; }

// Convenience: reduces `input` now and returns the value (one submit and wait).
template <class T>
T reduce_now(Context& context, ReduceOp op, const Buffer<T>& input) {
  Stream stream(context);
  Buffer<T> result(context, 1, "reduce result");
  reduce(stream, op, scalar_type_of<T>(), input, result);
  stream.submit_and_wait();
  return result.download()[0];
}

}  // namespace nf::gpu
