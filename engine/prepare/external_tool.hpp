#pragma once
// The programs prepare runs as subprocesses (COLMAP, ffmpeg, ffprobe): found on PATH or where an
// environment variable names them, run with their output appended to one log the user can read,
// and a failure quoted from that log.
#include <filesystem>
#include <string>
#include <vector>

namespace nf::prepare {

// The executable `name` on PATH, or the file the environment variable `override_variable` names.
// UsageError with `install_hint` (how to get it) when there is none.
std::string find_tool(const std::string& name, const char* override_variable, const std::string& install_hint);

// Runs `exe args...` with stdout and stderr appended to `log` (stdout to `stdout_file` instead when
// one is given). Returns the seconds it took. A failure throws InputError naming `label`, the exit
// status and the last lines of its output (the tool says there what went wrong), and the log.
double run_tool(const std::string& exe, const std::string& label, const std::vector<std::string>& args, const std::filesystem::path& log,
                const std::filesystem::path& stdout_file = {});

}  // namespace nf::prepare
