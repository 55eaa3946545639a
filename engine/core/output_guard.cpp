#include "engine/core/output_guard.hpp"

#include <fstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"

namespace nf {
namespace fs = std::filesystem;

bool path_inside(const fs::path& path, const fs::path& folder) {
  const fs::path rel = fs::weakly_canonical(fs::absolute(path)).lexically_relative(fs::weakly_canonical(fs::absolute(folder)));
  return !rel.empty() && *rel.begin() != "..";
}

void refuse_output_inside(const fs::path& out, const fs::path& input_folder, const std::string& option,
                          const std::string& what) {
  if (path_inside(out, input_folder))
    throw UsageError(option + " " + out.string() + " lies inside the " + what + " folder " + input_folder.string() +
                     "; nf_gpu never writes into its input, choose a folder outside it");
}

void require_folder_or_absent(const fs::path& path, const std::string& option) {
  std::error_code ec;
  if (fs::exists(path, ec) && !fs::is_directory(path, ec))
    throw InputError(option + " " + path.string() + " is an existing file, not a folder; choose a folder");
  for (fs::path up = fs::absolute(path).parent_path(); !up.empty(); up = up.parent_path()) {
    if (fs::exists(up, ec)) {
      if (!fs::is_directory(up, ec))
        throw InputError(option + " " + path.string() + ": " + up.string() + " is a file, not a folder; choose a path of folders");
      break;
    }
    if (up == up.parent_path()) break;
  }
}

void create_output_folder(const fs::path& dir, const std::string& option) {
  require_folder_or_absent(dir, option);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw InputError(option + " " + dir.string() + ": cannot create the folder" + (ec ? " (" + ec.message() + ")" : "") +
                     "; choose a folder you can write to");
}

OutputFolder::OutputFolder(fs::path dir, std::string option) : dir_(std::move(dir)), option_(std::move(option)) {
  create_output_folder(dir_, option_);
  std::ifstream record(dir_ / kRecordName);
  for (std::string line; std::getline(record, line);)
    if (!line.empty()) written_.insert(line);
  for (const std::string& name : remove_stale_temporaries(dir_)) log::info("removed ", (dir_ / name).string(), ", left by a run that was killed");
}

fs::path OutputFolder::claim(const std::string& name) {
  const fs::path path = dir_ / name;
  claimed_.insert(name);
  if (written_.count(name)) return path;
  std::error_code ec;
  if (fs::exists(fs::symlink_status(path, ec)))
    throw InputError(option_ + " " + dir_.string() + ": " + name + " exists and was not written by nf_gpu; it is "
                     "never replaced: choose an empty or new folder");
  written_.insert(name);
  std::string text;
  for (const std::string& n : written_) text += n + "\n";
  write_file_atomic(dir_ / kRecordName, text);
  return path;
}

std::vector<std::string> OutputFolder::finish() {
  std::vector<std::string> removed;
  std::error_code ec;
  for (const std::string& name : written_)
    if (!claimed_.count(name) && fs::remove(dir_ / name, ec)) removed.push_back(name);
  if (removed.empty() && written_ == claimed_) return removed;
  written_ = claimed_;
  std::string text;
  for (const std::string& n : written_) text += n + "\n";
  write_file_atomic(dir_ / kRecordName, text);
  if (!removed.empty()) log::info("removed ", removed.size(), " file(s) of an earlier run from ", dir_.string(), " (", removed.front(), removed.size() > 1 ? ", ..." : "", ")");
  return removed;
}

}  // namespace nf
