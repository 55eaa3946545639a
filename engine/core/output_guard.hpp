#pragma once
// Where commands write. An output never lies inside an input folder (after resolving `..` and
// symlinks), and a command never replaces a file that nf_gpu did not write: each output folder
// keeps a record (.nf_gpu_outputs) of the files nf_gpu wrote into it, and only those may be
// replaced by a later run. One guard for every command that writes. A folder holds one result of
// a command: finish() removes what an earlier run of the same command wrote there and this one
// did not (another command's files, an edit's beside a render's, stay).
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace nf {

// True when `path` is `folder` or lies inside it (both resolved through `..` and symlinks).
bool path_inside(const std::filesystem::path& path, const std::filesystem::path& folder);

// UsageError when `out` lies inside `input_folder`: "<option> OUT lies inside the <what> folder ...".
void refuse_output_inside(const std::filesystem::path& out, const std::filesystem::path& input_folder,
                          const std::string& option, const std::string& what);

// InputError when `path`, or a folder above it, exists and is not a folder (an `--out` that names
// a file, or a path under one).
void require_folder_or_absent(const std::filesystem::path& path, const std::string& option);
// Creates the folder (and those above it); InputError naming the option and saying why it cannot.
void create_output_folder(const std::filesystem::path& dir, const std::string& option);

class OutputFolder {
 public:
  // Creates the folder when missing. InputError when `dir` is an existing file or cannot be made.
  // `command` tags the files this run writes (edit, pose, render, ...).
  OutputFolder(std::filesystem::path dir, std::string command, std::string option = "--out");
  const std::filesystem::path& dir() const { return dir_; }
  // The path of `name` in the folder, claimed for writing: InputError when a file of that name
  // exists and nf_gpu did not write it here. The claim is recorded before the caller writes, so a
  // run killed mid-write may replace its own half-written file next time.
  std::filesystem::path claim(const std::string& name);
  // After a successful run: removes the files an earlier run of the same command recorded and this
  // run did not claim (another format, another view), so nothing stale sits beside the result.
  // Returns their names.
  std::vector<std::string> finish();

  static constexpr const char* kRecordName = ".nf_gpu_outputs";

 private:
  void save_record() const;

  std::filesystem::path dir_;
  std::string command_, option_;
  std::map<std::string, std::string> written_;  // every file nf_gpu wrote here -> the command that wrote it last
  std::set<std::string> claimed_;               // this run's
};

}  // namespace nf
