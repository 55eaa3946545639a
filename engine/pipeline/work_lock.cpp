#include "engine/pipeline/work_lock.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "engine/core/error.hpp"
#include "engine/core/host.hpp"
#include "engine/core/log.hpp"

namespace nf::pipeline {

namespace fs = std::filesystem;

namespace {

constexpr auto kHeartbeat = std::chrono::seconds(30);
// Ten missed heartbeats: a node that is merely slow (a loaded file server) is not taken from.
constexpr double kDefaultStaleSeconds = 300;

double stale_seconds() {
  if (const char* text = std::getenv("NF_WORK_LOCK_STALE_S")) {
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    if (end != text && *end == '\0' && v > 0) return v;
    log::warn("NF_WORK_LOCK_STALE_S='", text, "' is not a positive number of seconds: using ", kDefaultStaleSeconds);
  }
  return kDefaultStaleSeconds;
}

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Creates the file only when it does not exist, and writes our record into it.
bool create_exclusive(const fs::path& file, const std::string& text) {
  const int fd = open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (errno == EEXIST) return false;
    throw InputError("cannot create the lock '" + file.string() + "': " + std::strerror(errno));
  }
  const bool written = write(fd, text.data(), text.size()) == ssize_t(text.size());
  (void)fsync(fd);
  close(fd);
  if (!written) {
    fs::remove(file);
    throw InputError("cannot write the lock '" + file.string() + "' (disk full?)");
  }
  return true;
}

}  // namespace

json WorkLock::holder(const fs::path& work) {
  const std::string text = read_text(file(work));
  if (text.empty()) return json();
  try {
    const json j = json::parse(text);
    return j.is_object() ? j : json();
  } catch (const json::exception&) {
    return json();
  }
}

std::string WorkLock::stale_reason(const fs::path& work, const json& holder) {
  const std::string host = holder.value("host", std::string());
  const long pid = holder.value("pid", 0L);
  if (host == host_name()) {
    if (!process_alive(pid_t(pid))) return "its process " + std::to_string(pid) + " on this host has ended";
    return "";
  }
  std::error_code ec;
  const auto written = fs::last_write_time(file(work), ec);
  if (ec) return "";
  const double age = std::chrono::duration<double>(fs::file_time_type::clock::now() - written).count();
  const double limit = stale_seconds();
  if (age <= limit) return "";
  return "host '" + host + "' has not refreshed it for " + std::to_string(long(age)) + " s (limit " + std::to_string(long(limit)) +
         " s, NF_WORK_LOCK_STALE_S)";
}

WorkLock::WorkLock(const fs::path& work, const std::string& command) : path_(file(work)) {
  std::error_code ec;
  fs::create_directories(work, ec);
  if (ec) throw InputError("cannot create the WORK folder '" + work.string() + "': " + ec.message());
  token_ = json{{"host", host_name()}, {"pid", long(getpid())}, {"started", utc_now()}, {"command", command}}.dump() + "\n";
  // Two tries: the second after a stale lock was removed (another taker may win the race; then
  // its fresh lock is reported like any live one).
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (create_exclusive(path_, token_)) {
      thread_ = std::thread([this] { heartbeat(); });
      return;
    }
    const std::string seen = read_text(path_);
    json who;
    try {
      who = json::parse(seen);
    } catch (const json::exception&) {
    }
    const std::string reason = who.is_object() ? stale_reason(work, who) : "it is not a lock nf_gpu wrote";
    if (attempt == 0 && who.is_object() && !reason.empty()) {
      // Remove only the lock we judged: a taker that got there first has written another.
      if (read_text(path_) == seen) {
        log::warn("'", path_.string(), "' was held by ", who.value("host", std::string("?")), " (pid ", who.value("pid", 0L), "), but ", reason,
                  ": taking it over (the stages resume from their checkpoints)");
        fs::remove(path_, ec);
      }
      continue;
    }
    if (!who.is_object())
      throw InputError("'" + path_.string() + "' exists but " + reason + ": remove it if no nf_gpu run uses '" + work.string() + "'");
    throw InputError("'" + work.string() + "' is in use by another nf_gpu run: host " + who.value("host", std::string("?")) + ", pid " +
                     std::to_string(who.value("pid", 0L)) + ", since " + who.value("started", std::string("?")) + " (" +
                     who.value("command", std::string()) + "); wait for it, stop it, or use another --out (its lock: " +
                     path_.string() + ")");
  }
  throw InputError("'" + work.string() + "' is being taken by another nf_gpu run at this moment: try again");
}

void WorkLock::heartbeat() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!wake_.wait_for(lock, kHeartbeat, [this] { return stopping_; })) {
    std::error_code ec;
    fs::last_write_time(path_, fs::file_time_type::clock::now(), ec);
  }
}

WorkLock::~WorkLock() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::error_code ec;
  if (read_text(path_) == token_) fs::remove(path_, ec);
}

}  // namespace nf::pipeline
