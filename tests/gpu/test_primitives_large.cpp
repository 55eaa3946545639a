// Arrays larger than one binding (maxStorageBufferRange, 128 MiB on lavapipe): reduce and scan chunk
// transparently; compaction and sort refuse with an error that names the limit.
#include <doctest/doctest.h>

#include <numeric>

#include "engine/gpu/chunking.hpp"
#include "engine/gpu/compact.hpp"
#include "engine/gpu/radix_sort.hpp"
#include "engine/gpu/reduce.hpp"
#include "engine/gpu/scan.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::gpu;

TEST_CASE("reduce and scan span more than one binding range") {
  auto& ctx = test::context();
  const std::uint64_t per_binding = max_binding_elements(ctx, 4);
  const std::uint64_t n = per_binding + per_binding / 3 + 5;  // two chunks, the second partial
  if (n * 4 > ctx.info().limits.max_allocation_size) return;
  std::vector<std::uint32_t> v(n);
  for (std::uint64_t i = 0; i < n; ++i) v[i] = std::uint32_t((i * 2654435761u) >> 29);  // 0..7
  Buffer<std::uint32_t> in(ctx, std::span<const std::uint32_t>(v), "large input");
  std::uint32_t sum = 0, maxv = 0;
  for (auto x : v) sum += x, maxv = std::max(maxv, x);
  CHECK(reduce_now(ctx, ReduceOp::Sum, in) == sum);
  CHECK(reduce_now(ctx, ReduceOp::Max, in) == maxv);

  Buffer<std::uint32_t> total(ctx, 1, "total");
  Stream s(ctx);
  exclusive_scan(s, in, in, total);  // in place, to keep memory down
  s.submit_and_wait();
  CHECK(total.download()[0] == sum);
  const auto out = in.download();
  std::uint32_t running = 0;
  std::uint64_t mismatches = 0;
  for (std::uint64_t i = 0; i < n; ++i) {
    mismatches += out[i] != running;
    running += v[i];
  }
  CHECK(mismatches == 0);

  CHECK_THROWS_WITH_AS(radix_sort(s, in, {}, 32), doctest::Contains("maxStorageBufferRange"), DeviceError);
  Buffer<std::uint32_t> count(ctx, 1, "count");
  CHECK_THROWS_WITH_AS(compact(s, in, in, count), doctest::Contains("maxStorageBufferRange"), DeviceError);
}
