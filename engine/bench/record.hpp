#pragma once
// Building bench records: repeated timing with medians, and the common record fields.
#include <chrono>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/core/stats.hpp"
#include "engine/gpu/context.hpp"

namespace nf::bench {

struct Timing {
  std::vector<double> seconds;  // one per repeat
  std::vector<double> gpu_ms;   // summed pass times per repeat, when measured
  double median() const { return nf::median(seconds); }
};

// Runs `setup` (untimed) then `body` (timed) `repeats` times after one warm-up. `body` returns the
// GPU milliseconds it measured, or a negative number when it has none.
inline Timing time_repeats(int repeats, const std::function<void()>& setup, const std::function<double()>& body) {
  Timing t;
  for (int r = -1; r < repeats; ++r) {
    if (setup) setup();
    const auto start = std::chrono::steady_clock::now();
    const double gpu = body();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (r < 0) continue;  // warm-up: pipelines built, caches hot
    t.seconds.push_back(s);
    if (gpu >= 0) t.gpu_ms.push_back(gpu);
  }
  return t;
}

// Device milliseconds per run of each named pass the context timed since its totals were reset.
inline std::map<std::string, double> pass_ms_per_run(const gpu::Context& ctx, int runs) {
  std::map<std::string, double> out;
  for (const auto& [name, total] : ctx.pass_totals()) out[name] = total.milliseconds / runs;
  return out;
}

inline json make_record(const gpu::Context& context, const std::string& suite, const std::string& name,
                        const json& params, const Timing& timing, const json& metrics) {
  json r{{"suite", suite},
         {"case", name},
         {"device", context.info().name},
         {"driver", context.info().driver_info},
         {"params", params},
         {"repeats", timing.seconds.size()},
         {"seconds", {{"median", timing.median()}, {"min", minimum(timing.seconds)}, {"max", maximum(timing.seconds)}}},
         {"peak_device_bytes", context.peak_allocated_bytes()},
         {"metrics", metrics}};
  if (!timing.gpu_ms.empty()) r["gpu_ms"] = nf::median(timing.gpu_ms);
  return r;
}

}  // namespace nf::bench
