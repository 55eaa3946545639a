#pragma once
// COLMAP (Debian's `colmap`, CPU SIFT) run as a subprocess, one command per step, each step's
// output appended to one log file the user can read. The binary is `colmap` on PATH, or the file
// NF_COLMAP names.
#include <filesystem>
#include <string>
#include <vector>

namespace nf::prepare {

// The colmap executable to run; UsageError saying how to install it when there is none.
std::string colmap_executable();

// Runs `colmap <command> <args...>` with stdout and stderr appended to `log`. Returns the seconds it
// took. A failure throws InputError naming the step, the exit status and the last lines of its
// output (COLMAP says there what went wrong), and the log's path.
double run_colmap(const std::string& command, const std::vector<std::string>& args, const std::filesystem::path& log);

}  // namespace nf::prepare
