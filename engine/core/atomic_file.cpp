#include "engine/core/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <random>

#include "engine/core/error.hpp"
#include "engine/core/host.hpp"

namespace nf {

namespace {

constexpr std::string_view kTemporaryMark = ".tmp";
// A temporary of another host (a shared disk) is only judged by its age: its pid means nothing here.
constexpr auto kForeignTemporaryAge = std::chrono::hours(24);

// Why the last write failed, in words (a stream keeps no error of its own; errno is the system's).
std::string write_failure(int error) {
  if (error == EFBIG) return "the file-size limit was reached (ulimit -f)";
  if (error == ENOSPC) return "the disk is full";
  if (error == EDQUOT) return "the disk quota is used up";
  return error ? std::strerror(error) : "an unknown error";
}

}  // namespace

void write_file_atomic(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError("cannot create folder '" + dir.string() + "': " + ec.message());
  std::random_device rd;
  std::string tmp_name = ".";
  tmp_name += path.filename().string();
  tmp_name += kTemporaryMark;
  tmp_name += std::to_string(getpid());
  tmp_name += '-';
  tmp_name += std::to_string(rd());
  tmp_name += '@';
  tmp_name += host_name();
  const fs::path tmp = dir / tmp_name;
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw InputError("cannot write '" + tmp.string() + "': " + write_failure(errno));
      // The first failing write throws, so errno is the failure's (and no work follows it).
      out.exceptions(std::ios::badbit);
      try {
        write(out);
        out.flush();
      } catch (const std::ios_base::failure&) {
        const int error = errno;
        throw InputError("writing '" + path.string() + "' failed: " + write_failure(error) + "; nothing was left in its place");
      }
      out.exceptions(std::ios::goodbit);
      if (!out) throw InputError("writing '" + path.string() + "' failed: " + write_failure(errno) + "; nothing was left in its place");
      out.close();
      if (!out) throw InputError("writing '" + path.string() + "' failed: " + write_failure(errno) + "; nothing was left in its place");
    }
    // On a file server a rename can reach the disk before the data it names: sync both.
    if (const int error = sync_file(tmp))
      throw InputError("writing '" + path.string() + "' failed: " + write_failure(error) + "; nothing was left in its place");
    fs::rename(tmp, path, ec);
    if (ec) throw InputError("cannot move '" + tmp.string() + "' to '" + path.string() + "': " + ec.message());
    (void)sync_folder(dir);  // the file is complete under its name either way
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

std::vector<std::string> remove_stale_temporaries(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::vector<std::string> removed;
  const std::string here = host_name();
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    // ".NAME.tmpPID-RANDOM@HOST" (no "@HOST" from older versions: this host)
    const std::size_t mark = name.rfind(kTemporaryMark);
    if (name.empty() || name[0] != '.' || mark == std::string::npos) continue;
    const std::string tail = name.substr(mark + kTemporaryMark.size());
    const std::size_t dash = tail.find('-'), at = tail.find('@');
    if (dash == std::string::npos || (at != std::string::npos && at < dash)) continue;
    const std::string pid_text = tail.substr(0, dash);
    const std::string random_text = tail.substr(dash + 1, at == std::string::npos ? std::string::npos : at - dash - 1);
    const std::string host = at == std::string::npos ? here : tail.substr(at + 1);
    const auto digits = [](const std::string& s) { return !s.empty() && s.find_first_not_of("0123456789") == std::string::npos; };
    if (!digits(pid_text) || !digits(random_text) || pid_text.size() > 9) continue;
    if (host != here) {
      const auto age = fs::file_time_type::clock::now() - fs::last_write_time(e.path(), ec);
      if (ec || age < kForeignTemporaryAge) continue;
    } else {
      const pid_t pid = pid_t(std::stol(pid_text));
      if (pid == getpid() || process_alive(pid)) continue;  // its writer may still be at work
    }
    if (fs::remove(e.path(), ec)) removed.push_back(name);
  }
  return removed;
}

void write_file_atomic(const std::filesystem::path& path, std::string_view content) {
  write_file_atomic(path, [&](std::ostream& out) { out.write(content.data(), std::streamsize(content.size())); });
}

}  // namespace nf
