#pragma once
// The folder a scene suite works in: the one an environment variable names (kept, so that a second
// run reuses the scenes and the stages the first computed), else a temporary folder removed when
// the suite ends.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace nf::bench {

class ScratchFolder {
 public:
  ScratchFolder(const char* variable, const std::string& prefix) {
    const char* keep = std::getenv(variable);
    keep_ = keep != nullptr;
    path_ = keep_ ? std::filesystem::path(keep) : std::filesystem::temp_directory_path() / (prefix + std::to_string(::getpid()));
  }
  ~ScratchFolder() {
    std::error_code ec;
    if (!keep_) std::filesystem::remove_all(path_, ec);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  bool keep_ = false;
};

}  // namespace nf::bench
