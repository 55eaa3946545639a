#include "engine/core/host.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <ctime>

namespace nf {

std::string host_name() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0 || name[0] == '\0') return "localhost";
  std::string host(name);
  for (char& ch : host)
    if (ch == '/' || ch == '@') ch = '_';
  return host;
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm parts{};
  gmtime_r(&t, &parts);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &parts);
  return buf;
}

bool process_alive(pid_t pid) {
  if (pid <= 0) return false;
  return kill(pid, 0) == 0 || errno != ESRCH;
}

namespace {

int sync_path(const std::filesystem::path& path, int flags) {
  const int fd = open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) return 0;  // gone or unreadable: nothing of ours to lose
  const int result = fsync(fd) == 0 ? 0 : errno;
  close(fd);
  return result == EINVAL || result == EROFS || result == ENOTSUP || result == EBADF ? 0 : result;
}

}  // namespace

int sync_file(const std::filesystem::path& file) { return sync_path(file, O_RDONLY); }

int sync_folder(const std::filesystem::path& folder) { return sync_path(folder, O_RDONLY | O_DIRECTORY); }

int sync_tree(const std::filesystem::path& folder) {
  std::error_code ec;
  for (const auto& e : std::filesystem::recursive_directory_iterator(folder, ec)) {
    const int error = e.is_regular_file(ec) ? sync_file(e.path()) : e.is_directory(ec) ? sync_folder(e.path()) : 0;
    if (error) return error;
  }
  return sync_folder(folder);
}

}  // namespace nf
