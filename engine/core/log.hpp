#pragma once
// Minimal leveled logging to stderr. NF_LOG=debug|info|warn|error|quiet sets the threshold.
#include <sstream>
#include <string>

namespace nf::log {

enum class Level { Debug = 0, Info = 1, Warn = 2, Error = 3, Quiet = 4 };

Level threshold();
void write(Level level, const std::string& message);

template <class... Args>
std::string concat(const Args&... args) {
  std::ostringstream os;
  (os << ... << args);
  return os.str();
}

template <class... Args> void debug(const Args&... a) { if (threshold() <= Level::Debug) write(Level::Debug, concat(a...)); }
template <class... Args> void info(const Args&... a) { if (threshold() <= Level::Info) write(Level::Info, concat(a...)); }
template <class... Args> void warn(const Args&... a) { if (threshold() <= Level::Warn) write(Level::Warn, concat(a...)); }
template <class... Args> void error(const Args&... a) { if (threshold() <= Level::Error) write(Level::Error, concat(a...)); }

}  // namespace nf::log
