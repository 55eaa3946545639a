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
#include "engine/core/interrupt.hpp"
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
    if (!who.is_object())
      throw InputError("'" + path_.string() + "' exists but is not a lock nf_gpu wrote: remove it if no nf_gpu run uses '" +
                       work.string() + "'");
    const std::string reason = stale_reason(work, who);
    if (attempt == 0 && !reason.empty()) {
      // Rename what we judged aside: only one taker can, and it takes over only if the file it
      // moved is the one it judged (else it moved a fresh lock of a faster taker, and puts it back).
      const fs::path aside = path_.string() + ".stale-" + host_name() + "-" + std::to_string(getpid());
      fs::rename(path_, aside, ec);
      if (ec) continue;  // another taker moved it first
      if (read_text(aside) != seen) {
        if (link(aside.c_str(), path_.c_str()) != 0)
          log::warn("'", path_.string(), "' changed hands while it was being taken over; the other run will notice and stop");
        fs::remove(aside, ec);
        continue;
      }
      fs::remove(aside, ec);
      log::warn("'", path_.string(), "' was held by ", who.value("host", std::string("?")), " (pid ", who.value("pid", 0L), "), but ", reason,
                ": taking it over (the stages resume from their checkpoints)");
      continue;
    }
    throw WorkBusyError("'" + work.string() + "' is in use by another nf_gpu run: host " + who.value("host", std::string("?")) + ", pid " +
                        std::to_string(who.value("pid", 0L)) + ", since " + who.value("started", std::string("?")) + " (" +
                        who.value("command", std::string()) + "); wait for it, stop it, or use another --out (its lock: " +
                        path_.string() + ")");
  }
  throw WorkBusyError("'" + work.string() + "' is being taken by another nf_gpu run at this moment: try again");
}

void WorkLock::heartbeat() {
  const auto period = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::min(std::chrono::duration<double>(kHeartbeat), std::chrono::duration<double>(stale_seconds() / 10)));
  std::unique_lock<std::mutex> lock(mutex_);
  while (!wake_.wait_for(lock, period, [this] { return stopping_; })) {
    if (read_text(path_) != token_) {
      // Taken over while we were stopped past the limit (SIGSTOP, a suspended VM): two runs must
      // not write one WORK, so this one stops as Ctrl-C would.
      log::error("'", path_.string(), "' is no longer this run's lock (another run took it over): stopping");
      set_interrupted(true);
      return;
    }
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
