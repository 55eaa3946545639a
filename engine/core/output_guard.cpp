#include "engine/core/output_guard.hpp"

#include <fstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/text.hpp"

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

OutputFolder::OutputFolder(fs::path dir, std::string command, std::string option)
    : dir_(std::move(dir)), command_(std::move(command)), option_(std::move(option)) {
  create_output_folder(dir_, option_);
  // One line per file: "NAME<tab>COMMAND" ("NAME" alone in records of older versions).
  std::ifstream record(dir_ / kRecordName);
  for (std::string line; std::getline(record, line);) {
    if (line.empty()) continue;
    const std::size_t tab = line.find('\t');
    written_[line.substr(0, tab)] = tab == std::string::npos ? std::string() : line.substr(tab + 1);
  }
  for (const std::string& name : remove_stale_temporaries(dir_)) log::info("removed ", (dir_ / name).string(), ", left by a run that was killed");
}

fs::path OutputFolder::claim(const std::string& name) {
  const fs::path path = dir_ / name;
  claimed_.insert(name);
  const auto known = written_.find(name);
  if (known != written_.end() && known->second == command_) return path;
  std::error_code ec;
  if (known == written_.end() && fs::exists(fs::symlink_status(path, ec)))
    throw InputError(option_ + " " + dir_.string() + ": " + name + " exists and was not written by nf_gpu; it is "
                     "never replaced: choose an empty or new folder");
  written_[name] = command_;
  save_record();
  return path;
}

void OutputFolder::save_record() const {
  std::string text;
  for (const auto& [name, command] : written_) text += name + (command.empty() ? "" : "\t" + command) + "\n";
  write_file_atomic(dir_ / kRecordName, text);
}

std::vector<std::string> OutputFolder::finish() {
  NF_CHECK(!command_.empty(), "OutputFolder::finish needs the command that writes the folder");
  std::vector<std::string> removed;
  // A plain file name only: a record edited to hold "../x" or "/x" never removes anything outside.
  const auto plain = [](const std::string& n) { return !n.empty() && n != "." && n != ".." && n.find('/') == std::string::npos; };
  for (auto it = written_.begin(); it != written_.end();) {
    std::error_code ec;
    if (it->second == command_ && !claimed_.count(it->first) && plain(it->first)) {
      if (fs::remove(dir_ / it->first, ec) || !fs::exists(dir_ / it->first)) removed.push_back(it->first);
      it = written_.erase(it);
    } else {
      ++it;
    }
  }
  if (removed.empty()) return removed;
  save_record();
  log::warn("removed from ", dir_.string(), " what an earlier ", command_, " wrote there and this one did not: ", join(removed));
  return removed;
}

}  // namespace nf
