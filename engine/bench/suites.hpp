#pragma once
// `nf_gpu bench`: speed measured next to error, one JSON record per measurement.
// Record schema (shared by every suite): suite, case, device, driver, params {...}, repeats,
// seconds {median, min, max} (wall, host-observed), gpu_ms (median per-pass GPU time when the
// device has timestamps), peak_device_bytes, metrics {...} (throughputs, ratios, errors).
#include <string>
#include <vector>

#include "engine/core/json.hpp"

namespace nf::gpu {
class Context;
}

namespace nf::bench {

struct Options {
  std::string suite = "core";
  bool quick = false;       // smaller sizes and fewer repeats: a smoke run
  std::string torch_peer;   // path of tools/bench_torch_nn.py: run PyTorch on the CPU as a peer
};

std::vector<std::string> suite_names();
json run_suite(gpu::Context& context, const Options& options);
// Writes the records atomically: JSON lines for a `.jsonl` path, else one JSON array. A record may
// carry "curve": {"x", "y", "points": [[x, y], ...]}, an error-against-time series.
// InputError when a file at `path` exists and does not hold bench records (a JSON array of objects
// with "suite" and "case", or one such object per line): nf_gpu never replaces a file it did not
// write. The CLI checks before a suite runs; write_records checks again.
void check_records_file(const std::string& path);
void write_records(const std::string& path, const json& records);

}  // namespace nf::bench
