#include "engine/core/log.hpp"

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <mutex>

namespace nf::log {
namespace {

Level from_env() {
  const char* v = std::getenv("NF_LOG");
  if (!v) return Level::Info;
  if (!std::strcmp(v, "debug")) return Level::Debug;
  if (!std::strcmp(v, "warn")) return Level::Warn;
  if (!std::strcmp(v, "error")) return Level::Error;
  if (!std::strcmp(v, "quiet")) return Level::Quiet;
  return Level::Info;
}

std::atomic<Level>& current() {
  static std::atomic<Level> level{from_env()};
  return level;
}

}  // namespace

Level threshold() { return current().load(std::memory_order_relaxed); }

void write(Level level, const std::string& message) {
  static std::mutex mutex;
  static const char* names[] = {"debug", "info", "warning", "error", ""};
  std::lock_guard lock(mutex);
  std::cerr << "nf_gpu: " << names[static_cast<int>(level)] << ": " << message << '\n';
}

}  // namespace nf::log
