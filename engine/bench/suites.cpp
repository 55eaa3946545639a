#include "engine/bench/suites.hpp"

#include "engine/bench/core_suite.hpp"
#include "engine/bench/neus_suite.hpp"
#include "engine/bench/nn_suite.hpp"
#include "engine/bench/splat_suite.hpp"
#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"

namespace nf::bench {

std::vector<std::string> suite_names() { return {"core", "nn", "splat", "neus"}; }

json run_suite(gpu::Context& context, const Options& options) {
  if (options.suite == "core") return run_core_suite(context, options);
  if (options.suite == "nn") return run_nn_suite(context, options);
  if (options.suite == "splat") return run_splat_suite(context, options);
  if (options.suite == "neus") return run_neus_suite(context, options);
  throw UsageError("unknown bench suite '" + options.suite + "'");
}

void write_records(const std::string& path, const json& records) {
  // `.jsonl`: one record per line (easy to append and stream); anything else: one JSON array.
  if (path.size() > 6 && path.substr(path.size() - 6) == ".jsonl") {
    std::string lines;
    for (const auto& r : records) lines += r.dump() + "\n";
    write_file_atomic(path, lines);
    return;
  }
  write_file_atomic(path, records.dump(2) + "\n");
}

}  // namespace nf::bench
