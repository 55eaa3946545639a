#include "engine/bench/suites.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "engine/bench/body_suite.hpp"
#include "engine/bench/fur_suite.hpp"
#include "engine/bench/core_suite.hpp"
#include "engine/bench/neus_suite.hpp"
#include "engine/bench/nn_suite.hpp"
#include "engine/bench/splat_suite.hpp"
#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"

namespace nf::bench {

std::vector<std::string> suite_names() { return {"core", "nn", "splat", "neus", "body", "fur"}; }

json run_suite(gpu::Context& context, const Options& options) {
  if (options.suite == "core") return run_core_suite(context, options);
  if (options.suite == "nn") return run_nn_suite(context, options);
  if (options.suite == "splat") return run_splat_suite(context, options);
  if (options.suite == "neus") return run_neus_suite(context, options);
  if (options.suite == "body") return run_body_suite(context, options);
  if (options.suite == "fur") return run_fur_suite(context, options);
  throw UsageError("unknown bench suite '" + options.suite + "'");
}

void check_records_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) return;
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  const auto is_record = [](const json& r) { return r.is_object() && r.contains("suite") && r.contains("case"); };
  json whole = json::parse(text, nullptr, false);
  bool ours = whole.is_array() && std::all_of(whole.begin(), whole.end(), is_record);
  if (!ours && !text.empty()) {
    ours = true;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);)
      if (!line.empty()) ours &= is_record(json::parse(line, nullptr, false));
  }
  if (!ours && !text.empty())
    throw InputError("--json " + path + " exists and does not hold nf_gpu bench records; it is never replaced: choose "
                     "another file");
}

void write_records(const std::string& path, const json& records) {
  check_records_file(path);
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
