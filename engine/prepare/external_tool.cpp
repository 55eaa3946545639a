#include "engine/prepare/external_tool.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/stopwatch.hpp"

extern char** environ;

namespace nf::prepare {

namespace fs = std::filesystem;

std::string find_tool(const std::string& name, const char* override_variable, const std::string& install_hint) {
  if (const char* named = std::getenv(override_variable); named && *named) {
    if (access(named, X_OK) != 0) throw UsageError(std::string(override_variable) + " names " + named + ", which is not an executable file");
    return named;
  }
  if (const char* path = std::getenv("PATH"))
    for (std::string dirs = path; !dirs.empty();) {
      const std::size_t colon = dirs.find(':');
      const fs::path candidate = fs::path(dirs.substr(0, colon)) / name;
      if (access(candidate.c_str(), X_OK) == 0) return candidate.string();
      dirs = colon == std::string::npos ? "" : dirs.substr(colon + 1);
    }
  throw UsageError(install_hint);
}

namespace {

std::string last_lines(const fs::path& log, std::streamoff from, std::size_t count) {
  std::ifstream in(log);
  in.seekg(from);
  std::deque<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    if (line.find_first_not_of(" \t\r=") == std::string::npos) continue;
    lines.push_back(line);
    if (lines.size() > count) lines.pop_front();
  }
  std::string text;
  for (const std::string& line : lines) text += "\n  " + line;
  return text;
}

int open_for_append(const fs::path& file, const std::string& what) {
  const int fd = open(file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(file.string() + ": cannot open " + what + " for writing (" + std::strerror(errno) + ")");
  return fd;
}

}  // namespace

double run_tool(const std::string& exe, const std::string& label, const std::vector<std::string>& args, const fs::path& log, const fs::path& stdout_file) {
  std::vector<std::string> words = {exe};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);

  const int fd = open_for_append(log, "the log of " + label);
  const int out_fd = stdout_file.empty() ? fd : open(stdout_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (out_fd < 0) {
    close(fd);
    throw InputError(stdout_file.string() + ": cannot open for writing (" + std::strerror(errno) + ")");
  }
  const std::streamoff start = lseek(fd, 0, SEEK_END);
  const std::string banner = "\n$ " + label + "\n";
  (void)!write(fd, banner.data(), banner.size());
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out_fd, STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, fd, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  Stopwatch clock;
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fd);
  if (out_fd != fd) close(out_fd);
  if (spawned != 0) throw InputError(label + ": cannot start " + exe + " (" + std::strerror(spawned) + ")");
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) throw InputError(label + ": lost track of " + exe + " (" + std::strerror(errno) + ")");
  const double seconds = clock.seconds();
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  if (code != 0)
    throw InputError(label + " failed (exit status " + std::to_string(code) + "); its last lines:" + last_lines(log, start, 8) +
                     "\nthe whole output is in " + log.string());
  log::info("prepare: ", label, " in ", std::to_string(seconds).substr(0, 5), " s");
  return seconds;
}

}  // namespace nf::prepare
