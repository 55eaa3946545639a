#pragma once
// Running the nf_gpu binary from a test (NF_GPU_BINARY, set by tests/CMakeLists.txt): in the
// foreground with its exit code and output, or in the background to signal it.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <doctest/doctest.h>

#include "engine/core/json.hpp"
#include "tests/support/files.hpp"

namespace nf::test {

struct Result {
  int code;
  std::string output;  // stdout and stderr together
};

inline Result run(const std::string& args, const std::string& env = "") {
  const std::string command = env + " " + std::string(NF_GPU_BINARY) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  REQUIRE(pipe != nullptr);
  Result r{0, {}};
  char buffer[4096];
  while (std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) r.output.append(buffer, n);
  const int status = pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// The JSON document a --json command printed: from the first line that opens an array or object
// (log lines before it may hold brackets of their own).
inline json json_in(const std::string& output) {
  std::size_t at = 0;
  while (at < output.size() && output[at] != '[' && output[at] != '{') {
    at = output.find('\n', at);
    if (at == std::string::npos) break;
    ++at;
  }
  INFO("no JSON document in the output:\n", output);
  REQUIRE((at != std::string::npos && at < output.size()));
  return json::parse(output.substr(at));
}
inline json json_of(const Result& r) { return json_in(r.output); }

// reconstruct's stages in their order, as `nf_gpu reconstruct --help` lists them: a test that walks
// every stage follows the binary's list rather than keeping a copy of its own (asked once a process).
inline std::vector<std::string> read_stage_names() {
  const Result help = run("reconstruct --help");
  const std::string marker = "stages, in order: ";
  const std::size_t at = help.output.find(marker);
  INFO(help.output);
  REQUIRE(at != std::string::npos);
  const std::string line = help.output.substr(at + marker.size(), help.output.find('\n', at) - at - marker.size());
  std::vector<std::string> names;
  for (std::size_t from = 0; from <= line.size();) {
    const std::size_t comma = std::min(line.find(", ", from), line.size());
    names.push_back(line.substr(from, comma - from));
    from = comma + 2;
  }
  REQUIRE(names.size() >= 2);
  return names;
}
inline const std::vector<std::string>& stage_names() {
  static const std::vector<std::string> names = read_stage_names();
  return names;
}

// Starts nf_gpu in the background with its output going to `log`.
inline pid_t spawn(const std::string& args, const std::filesystem::path& log) {
  const std::string command = "exec " + std::string(NF_GPU_BINARY) + " " + args + " > " + log.string() + " 2>&1";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

// Waits until `log` holds `text` (true) or `seconds` pass (false).
inline bool wait_for(const std::filesystem::path& log, const std::string& text, double seconds) {
  for (int i = 0; i < int(seconds * 20); ++i) {
    if (slurp(log).find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

inline int wait_exit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}


}  // namespace nf::test
