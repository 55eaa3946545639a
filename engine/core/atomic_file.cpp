#include "engine/core/atomic_file.hpp"

#include <unistd.h>

#include <fstream>
#include <random>

#include "engine/core/error.hpp"

namespace nf {

void write_file_atomic(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError("cannot create folder '" + dir.string() + "': " + ec.message());
  std::random_device rd;
  std::string tmp_name = ".";
  tmp_name += path.filename().string();
  tmp_name += ".tmp";
  tmp_name += std::to_string(getpid());
  tmp_name += '-';
  tmp_name += std::to_string(rd());
  const fs::path tmp = dir / tmp_name;
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw InputError("cannot write '" + tmp.string() + "'");
      write(out);
      out.flush();
      if (!out) throw InputError("writing '" + path.string() + "' failed (disk full?)");
    }
    fs::rename(tmp, path, ec);
    if (ec) throw InputError("cannot move '" + tmp.string() + "' to '" + path.string() + "': " + ec.message());
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

void write_file_atomic(const std::filesystem::path& path, std::string_view content) {
  write_file_atomic(path, [&](std::ostream& out) { out.write(content.data(), std::streamsize(content.size())); });
}

}  // namespace nf
