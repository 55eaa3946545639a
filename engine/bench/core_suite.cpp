#include "engine/bench/core_suite.hpp"

#include <algorithm>
#include <numeric>
#include <random>

#include "engine/bench/record.hpp"
#include "engine/core/error.hpp"
#include "engine/core/progress.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/gpu/radix_sort.hpp"
#include "engine/gpu/reduce.hpp"
#include "engine/gpu/scan.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::bench {
namespace {

constexpr const char* kSuite = "core";

struct CopyPush {
  std::uint32_t n;
};
struct FmaPush {
  std::uint32_t iterations;
  float a, b;
};

double pass_ms(const gpu::Stream& s) {
  double ms = 0;
  for (const auto& p : s.last_pass_times()) ms += p.milliseconds;
  return s.last_pass_times().empty() ? -1.0 : ms;
}

std::vector<std::uint32_t> random_keys(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::uint32_t> v(n);
  for (auto& x : v) x = rng();
  return v;
}

json copy_records(gpu::Context& ctx, bool quick, int repeats) {
  json out = json::array();
  const std::uint64_t bytes = (quick ? 16ull : 64ull) << 20;
  gpu::Buffer<float> src(ctx, bytes / 4, "bench copy source"), dst(ctx, bytes / 4, "bench copy destination");
  src.fill_u32(0x3f800000u);
  gpu::Stream s(ctx);
  const json params{{"bytes", bytes}};

  const Timing transfer = time_repeats(repeats, nullptr, [&] {
    s.begin_pass("bench/copy_transfer");
    s.copy(src, dst);
    s.end_pass();
    s.submit_and_wait();
    return pass_ms(s);
  });
  json m{{"GBps_wall", double(bytes) / transfer.median() / 1e9}};
  if (!transfer.gpu_ms.empty()) m["GBps_gpu"] = double(bytes) / (median(transfer.gpu_ms) * 1e-3) / 1e9;
  m["note"] = "bytes copied per second; memory traffic is twice that (read + write)";
  out.push_back(make_record(ctx, kSuite, "copy_transfer", params, transfer, m));

  const gpu::Kernel& copy = ctx.kernel("bench/core_copy", {{0, 256}});
  const std::uint32_t vec4s = std::uint32_t(bytes / 16);
  const Timing shader = time_repeats(repeats, nullptr, [&] {
    s.begin_pass("bench/copy_shader");
    s.dispatch(copy, {src, dst}, CopyPush{vec4s}, gpu::Elements(vec4s));
    s.end_pass();
    s.submit_and_wait();
    return pass_ms(s);
  });
  json m2{{"GBps_wall", double(bytes) / shader.median() / 1e9}};
  if (!shader.gpu_ms.empty()) m2["GBps_gpu"] = double(bytes) / (median(shader.gpu_ms) * 1e-3) / 1e9;
  out.push_back(make_record(ctx, kSuite, "copy_shader", params, shader, m2));
  return out;
}

json fma_record(gpu::Context& ctx, bool quick, int repeats) {
  const std::uint32_t invocations = quick ? 16384 : 65536, iterations = quick ? 256 : 1024;
  gpu::Buffer<float> sink(ctx, std::uint64_t(invocations) * 4, "bench fma sink");
  const gpu::Kernel& fma = ctx.kernel("bench/core_fma", {{0, 256}});
  gpu::Stream s(ctx);
  const Timing t = time_repeats(repeats, nullptr, [&] {
    s.begin_pass("bench/fma");
    s.dispatch(fma, {sink}, FmaPush{iterations, 0.999f, 0.001f}, gpu::Elements(invocations));
    s.end_pass();
    s.submit_and_wait();
    return pass_ms(s);
  });
  // iterations: a multiple of core_fma's unroll (32); 16 vec4 FMAs each, 2 flops per lane.
  const double flops = double(invocations) * iterations * 16 * 4 * 2;
  json m{{"GFLOPs_wall", flops / t.median() / 1e9}};
  if (!t.gpu_ms.empty()) m["GFLOPs_gpu"] = flops / (median(t.gpu_ms) * 1e-3) / 1e9;
  return make_record(ctx, kSuite, "fma_f32", {{"invocations", invocations}, {"iterations", iterations}}, t, m);
}

json latency_records(gpu::Context& ctx, bool quick, int repeats) {
  json out = json::array();
  const std::uint32_t dispatches = quick ? 200 : 1000;
  const std::uint64_t slot = 64;  // floats: 256-byte slots keep every binding offset aligned
  gpu::Buffer<float> a(ctx, dispatches * slot, "bench latency a"), b(ctx, dispatches * slot, "bench latency b");
  const gpu::Kernel& copy = ctx.kernel("bench/core_copy", {{0, 64}});
  gpu::Stream s(ctx);
  auto run = [&](std::uint32_t count, bool barriers) {
    return time_repeats(repeats, nullptr, [&] {
      for (std::uint32_t i = 0; i < count; ++i) {
        s.dispatch(copy, {a.range(i * slot, slot), b.range(i * slot, slot)}, CopyPush{1}, gpu::Elements(1));
        if (barriers) s.barrier();
      }
      s.submit_and_wait();
      return -1.0;
    });
  };
  const Timing one = run(1, false), many = run(dispatches, false), fenced = run(dispatches, true);
  const Timing empty = time_repeats(repeats * 4, nullptr, [&] {
    s.submit_and_wait();
    return -1.0;
  });
  const double per_dispatch = (many.median() - one.median()) / (dispatches - 1);
  const double per_fenced = (fenced.median() - one.median()) / (dispatches - 1);
  out.push_back(make_record(ctx, kSuite, "dispatch_latency", {{"dispatches", dispatches}}, many,
                            {{"us_per_dispatch", per_dispatch * 1e6}, {"us_per_dispatch_with_barrier", per_fenced * 1e6}}));
  out.push_back(make_record(ctx, kSuite, "submit_latency", {{"dispatches", 1}}, one,
                            {{"us_submit_wait_one_dispatch", one.median() * 1e6},
                             {"us_submit_wait_empty", empty.median() * 1e6}}));
  return out;
}

json sort_records(gpu::Context& ctx, bool quick, int repeats) {
  json out = json::array();
  const std::size_t n = quick ? (1u << 18) : (1u << 22);
  const auto keys = random_keys(n, 42);
  std::vector<std::uint32_t> index(n);
  std::iota(index.begin(), index.end(), 0u);
  gpu::Buffer<std::uint32_t> d_keys(ctx, n, "bench sort keys"), d_values(ctx, n, "bench sort values");
  gpu::Stream s(ctx);
  const Timing gpu_t = time_repeats(
      repeats,
      [&] {
        d_keys.upload(keys);
        d_values.upload(index);
      },
      [&] {
        s.begin_pass("bench/radix_sort");
        gpu::radix_sort(s, d_keys, d_values, 32);
        s.end_pass();
        s.submit_and_wait();
        return pass_ms(s);
      });

  // Peers in the same run: std::sort and std::stable_sort of (key, value) pairs.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs(n), work;
  for (std::size_t i = 0; i < n; ++i) pairs[i] = {keys[i], index[i]};
  const auto by_key = [](const auto& x, const auto& y) { return x.first < y.first; };
  const Timing std_t = time_repeats(repeats, [&] { work = pairs; }, [&] {
    std::sort(work.begin(), work.end(), by_key);
    return -1.0;
  });
  const Timing stable_t = time_repeats(repeats, [&] { work = pairs; }, [&] {
    std::stable_sort(work.begin(), work.end(), by_key);
    return -1.0;
  });

  // Error: the GPU result must equal the stable reference exactly.
  const auto got_keys = d_keys.download(), got_values = d_values.download();
  std::uint64_t mismatches = 0;
  for (std::size_t i = 0; i < n; ++i) mismatches += got_keys[i] != work[i].first || got_values[i] != work[i].second;

  const json params{{"n", n}, {"key_bits", 32}, {"values", true}};
  out.push_back(make_record(ctx, kSuite, "radix_sort_kv32", params, gpu_t,
                            {{"Mkeys_per_s", double(n) / gpu_t.median() / 1e6},
                             {"std_sort_Mkeys_per_s", double(n) / std_t.median() / 1e6},
                             {"std_stable_sort_Mkeys_per_s", double(n) / stable_t.median() / 1e6},
                             {"speedup_vs_std_sort", std_t.median() / gpu_t.median()},
                             {"speedup_vs_std_stable_sort", stable_t.median() / gpu_t.median()},
                             {"mismatches_vs_std_stable_sort", mismatches}}));
  out.push_back(make_record(ctx, kSuite, "std_sort_kv32", params, std_t, {{"Mkeys_per_s", double(n) / std_t.median() / 1e6}}));
  return out;
}

json scan_reduce_records(gpu::Context& ctx, bool quick, int repeats) {
  json out = json::array();
  const std::size_t n = quick ? (1u << 20) : (1u << 24);
  std::vector<std::uint32_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = std::uint32_t(i % 7);
  gpu::Buffer<std::uint32_t> in(ctx, std::span<const std::uint32_t>(v), "bench scan input");
  gpu::Buffer<std::uint32_t> result(ctx, n, "bench scan output"), total(ctx, 1, "bench scan total");
  gpu::Stream s(ctx);
  const Timing scan_t = time_repeats(repeats, nullptr, [&] {
    s.begin_pass("bench/exclusive_scan");
    gpu::exclusive_scan(s, in, result, total);
    s.end_pass();
    s.submit_and_wait();
    return pass_ms(s);
  });
  std::uint64_t expected_total = 0;
  for (auto x : v) expected_total += x;
  out.push_back(make_record(ctx, kSuite, "exclusive_scan_u32", {{"n", n}}, scan_t,
                            {{"Melements_per_s", double(n) / scan_t.median() / 1e6},
                             {"total_error", double(total.download()[0]) - double(expected_total)}}));
  const Timing reduce_t = time_repeats(repeats, nullptr, [&] {
    s.begin_pass("bench/reduce_sum");
    gpu::reduce(s, gpu::ReduceOp::Sum, gpu::ScalarType::U32, in, total);
    s.end_pass();
    s.submit_and_wait();
    return pass_ms(s);
  });
  out.push_back(make_record(ctx, kSuite, "reduce_sum_u32", {{"n", n}}, reduce_t,
                            {{"GBps_wall", double(n) * 4 / reduce_t.median() / 1e9},
                             {"error", double(total.download()[0]) - double(expected_total)}}));
  return out;
}

}  // namespace

double measure_fma_gflops(gpu::Context& context, bool quick) {
  const json r = fma_record(context, quick, 3);
  return r["metrics"]["GFLOPs_wall"].get<double>();
}

double measure_copy_traffic_gbps(gpu::Context& context, bool quick) {
  const json records = copy_records(context, quick, 3);
  for (const json& r : records)
    if (r["case"] == "copy_shader") return 2 * r["metrics"]["GBps_wall"].get<double>();
  throw InternalError("bench: no copy_shader record");
}

json run_core_suite(gpu::Context& context, const Options& options) {
  const int repeats = options.quick ? 3 : 7;
  json records = json::array();
  Progress progress("bench core", 5);
  const auto add = [&](const json& r) {
    if (r.is_array())
      for (const auto& x : r) records.push_back(x);
    else
      records.push_back(r);
  };
  add(copy_records(context, options.quick, repeats));
  progress.update(1, "copy");
  add(fma_record(context, options.quick, repeats));
  progress.update(2, "fma");
  add(latency_records(context, options.quick, repeats));
  progress.update(3, "latency");
  add(sort_records(context, options.quick, repeats));
  progress.update(4, "sort");
  add(scan_reduce_records(context, options.quick, repeats));
  progress.finish("done");
  return records;
}

}  // namespace nf::bench
