#pragma once
// Whole-file reads and writes for tests that corrupt files on purpose.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <system_error>
#include <vector>

namespace nf::test {

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline void spit(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

// Every file under `dir` (relative path -> bytes).
inline std::map<std::string, std::string> snapshot(const std::filesystem::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files[std::filesystem::relative(e.path(), dir).string()] = slurp(e.path());
  return files;
}

// Removes `path` (a file or a folder) when the process exits normally: a test run is many processes,
// each naming its scratch paths by its pid, and each would otherwise leave them in /tmp.
inline void remove_at_exit(const std::filesystem::path& path) {
  struct Paths {
    std::vector<std::filesystem::path> list;
    ~Paths() {
      for (const auto& p : list) {
        std::error_code ignored;
        std::filesystem::remove_all(p, ignored);
      }
    }
  };
  static Paths paths;
  for (const auto& p : paths.list)
    if (p == path) return;
  paths.list.push_back(path);
}

}  // namespace nf::test
