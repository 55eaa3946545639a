// Reduce, exclusive scan, compaction and radix sort against std:: references, over the sizes and
// key patterns where such kernels usually break. ctest runs this suite at several lavapipe
// vector widths (subgroups of 4, 8 and 16 lanes).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "engine/gpu/compact.hpp"
#include "engine/gpu/radix_sort.hpp"
#include "engine/gpu/reduce.hpp"
#include "engine/gpu/scan.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
using namespace nf::gpu;

namespace {

const std::vector<std::size_t> kSizes = {0, 1, 2, 7, 255, 257, 1023, 1025, 2047, 2049, 65535, 65537, (1u << 20) - 1,
                                         (1u << 20) + 1};

std::vector<std::uint32_t> sort_input(const std::string& pattern, std::size_t n, std::uint32_t seed) {
  if (pattern == "equal") return std::vector<std::uint32_t>(n, 0xdeadbeefu);
  auto v = test::random_u32(n, seed);
  if (pattern == "sorted") std::sort(v.begin(), v.end());
  if (pattern == "reversed") std::sort(v.rbegin(), v.rend());
  if (pattern == "few") for (auto& x : v) x %= 3;
  return v;
}

}  // namespace

TEST_CASE("reduce sum/min/max of float, uint and int matches the std reference") {
  auto& ctx = test::context();
  for (std::size_t n : kSizes) {
    CAPTURE(n);
    const auto f = test::random_f32(n, 11 + std::uint32_t(n), -3.f, 5.f);
    Buffer<float> bf(ctx, std::span<const float>(f), "floats");
    double exact = 0, magnitude = 0;
    for (float x : f) exact += x, magnitude += std::fabs(x);
    CHECK(std::fabs(reduce_now(ctx, ReduceOp::Sum, bf) - exact) <= 1e-5 * magnitude + 1e-6);
    const float fmin = n ? *std::min_element(f.begin(), f.end()) : INFINITY;
    const float fmax = n ? *std::max_element(f.begin(), f.end()) : -INFINITY;
    CHECK(reduce_now(ctx, ReduceOp::Min, bf) == fmin);
    CHECK(reduce_now(ctx, ReduceOp::Max, bf) == fmax);

    const auto u = test::random_u32(n, 5 + std::uint32_t(n), 1000);
    Buffer<std::uint32_t> bu(ctx, std::span<const std::uint32_t>(u), "uints");
    CHECK(reduce_now(ctx, ReduceOp::Sum, bu) == std::accumulate(u.begin(), u.end(), 0u));
    CHECK(reduce_now(ctx, ReduceOp::Min, bu) == (n ? *std::min_element(u.begin(), u.end()) : 0xffffffffu));
    CHECK(reduce_now(ctx, ReduceOp::Max, bu) == (n ? *std::max_element(u.begin(), u.end()) : 0u));

    std::vector<std::int32_t> i(n);
    for (std::size_t k = 0; k < n; ++k) i[k] = std::int32_t(u[k]) - 500;
    Buffer<std::int32_t> bi(ctx, std::span<const std::int32_t>(i), "ints");
    CHECK(reduce_now(ctx, ReduceOp::Sum, bi) == std::accumulate(i.begin(), i.end(), 0));
    CHECK(reduce_now(ctx, ReduceOp::Min, bi) == (n ? *std::min_element(i.begin(), i.end()) : INT32_MAX));
    CHECK(reduce_now(ctx, ReduceOp::Max, bi) == (n ? *std::max_element(i.begin(), i.end()) : INT32_MIN));
  }
}

TEST_CASE("exclusive scan matches std::exclusive_scan, in place and out of place") {
  auto& ctx = test::context();
  for (std::size_t n : kSizes) {
    CAPTURE(n);
    const auto v = test::random_u32(n, 3 + std::uint32_t(n), 100);
    std::vector<std::uint32_t> expected(n);
    std::exclusive_scan(v.begin(), v.end(), expected.begin(), 0u);
    const std::uint32_t sum = std::accumulate(v.begin(), v.end(), 0u);
    Buffer<std::uint32_t> in(ctx, std::span<const std::uint32_t>(v), "scan in");
    Buffer<std::uint32_t> out(ctx, n, "scan out"), total(ctx, 1, "scan total");
    Stream s(ctx);
    exclusive_scan(s, in, out, total);
    s.submit_and_wait();
    CHECK(out.download() == expected);
    CHECK(total.download()[0] == sum);
    exclusive_scan(s, in, in);  // in place
    s.submit_and_wait();
    CHECK(in.download() == expected);
  }
}

TEST_CASE("compaction keeps flagged indices and values in order") {
  auto& ctx = test::context();
  for (std::size_t n : kSizes) {
    for (int density : {0, 1, 50, 100}) {
      CAPTURE(n);
      CAPTURE(density);
      auto flags = test::random_u32(n, 17 + std::uint32_t(n), 99);
      for (auto& f : flags) f = f < std::uint32_t(density) ? 7u : 0u;  // any non-zero value counts
      const auto values = test::random_u32(n, 23);
      std::vector<std::uint32_t> kept_idx, kept_val;
      for (std::size_t i = 0; i < n; ++i)
        if (flags[i]) kept_idx.push_back(std::uint32_t(i)), kept_val.push_back(values[i]);
      Buffer<std::uint32_t> bflags(ctx, std::span<const std::uint32_t>(flags), "flags");
      Buffer<std::uint32_t> bvalues(ctx, std::span<const std::uint32_t>(values), "values");
      Buffer<std::uint32_t> out_idx(ctx, n, "kept indices"), out_val(ctx, n, "kept values"), count(ctx, 1, "count");
      Stream s(ctx);
      compact(s, bflags, out_idx, count);
      s.submit_and_wait();
      const std::uint32_t kept = count.download()[0];
      REQUIRE(kept == kept_idx.size());
      CHECK(out_idx.download(0, kept) == kept_idx);
      compact(s, bflags, out_val, count, bvalues);
      s.submit_and_wait();
      CHECK(out_val.download(0, kept) == kept_val);
    }
  }
}

TEST_CASE("radix sort is a stable key-value sort for every pattern and size") {
  auto& ctx = test::context();
  for (const std::string pattern : {"random", "equal", "sorted", "reversed", "few"}) {
    for (std::size_t n : kSizes) {
      CAPTURE(pattern);
      CAPTURE(n);
      const auto keys = sort_input(pattern, n, 101 + std::uint32_t(n));
      std::vector<std::uint32_t> order(n);
      std::iota(order.begin(), order.end(), 0u);
      std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
      std::vector<std::uint32_t> sorted_keys(n);
      for (std::size_t i = 0; i < n; ++i) sorted_keys[i] = keys[order[i]];
      Buffer<std::uint32_t> k(ctx, std::span<const std::uint32_t>(keys), "keys");
      Buffer<std::uint32_t> v(ctx, n, "values");
      std::vector<std::uint32_t> identity(n);
      std::iota(identity.begin(), identity.end(), 0u);
      v.upload(identity);
      Stream s(ctx);
      radix_sort(s, k, v, 32);
      s.submit_and_wait();
      CHECK(k.download() == sorted_keys);
      CHECK(v.download() == order);  // equal keys keep their input order
    }
  }
}

TEST_CASE("radix sort of the low bits only: odd pass counts, keys-only") {
  auto& ctx = test::context();
  for (std::uint32_t bits : {1u, 4u, 10u, 13u, 20u, 31u}) {
    CAPTURE(bits);
    const std::uint32_t mask = bits == 32 ? 0xffffffffu : (1u << bits) - 1;
    auto keys = test::random_u32(100003, bits, mask);
    Buffer<std::uint32_t> k(ctx, std::span<const std::uint32_t>(keys), "keys");
    Stream s(ctx);
    radix_sort(s, k, {}, bits);
    s.submit_and_wait();
    std::sort(keys.begin(), keys.end());
    CHECK(k.download() == keys);
  }
  CHECK(key_bits_for(0) == 1);
  CHECK(key_bits_for(1) == 1);
  CHECK(key_bits_for(1023) == 10);
  CHECK(key_bits_for(1024) == 11);
}
