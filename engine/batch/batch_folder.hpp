#pragma once
// A batch's own folder (`nf_gpu batch run --out DIR`, default <manifest>.batch beside it):
//   batch.json        the tasks as run (resolved manifest), the nf_gpu binary, the submissions
//   tasks/NAME.json   each task's state, written atomically by the task itself
//   logs/NAME.log     each task's output, appended across attempts
//   batch.sbatch      the Slurm job array (slurm backend)
// The scenes' results stay in their WORK folders; status and reports read both.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "engine/batch/manifest.hpp"
#include "engine/core/json.hpp"

namespace nf::batch {

// What a task's state file says. "pending" (never started), "queued" (submitted to Slurm),
// "running", "done", "failed" (a rerun cannot fix it: bad input or usage), "stopped" (a signal or
// a device error: a rerun resumes), "requeued" (stopped, and Slurm was asked to run it again),
// "unreadable" (the file is damaged; the message says which).
struct TaskState {
  std::string state = "pending";
  int attempts = 0;
  std::string host, started, ended, job, message;
  long pid = 0;
  int exit_code = 0;
};

class BatchFolder {
 public:
  explicit BatchFolder(std::filesystem::path dir) : dir_(std::move(dir)) {}
  const std::filesystem::path& dir() const { return dir_; }
  std::filesystem::path record() const { return dir_ / "batch.json"; }
  std::filesystem::path state_file(const std::string& task) const { return dir_ / "tasks" / (task + ".json"); }
  std::filesystem::path log_file(const std::string& task) const { return dir_ / "logs" / (task + ".log"); }
  std::filesystem::path sbatch_script() const { return dir_ / "batch.sbatch"; }

  // Writes batch.json for these tasks (keeping earlier submissions), creating the folders.
  void write(const std::vector<BatchTask>& tasks, const std::filesystem::path& manifest, const std::filesystem::path& nf_gpu) const;
  // InputError naming the folder when it holds no batch.json.
  json read() const;
  std::vector<BatchTask> tasks() const;
  std::filesystem::path nf_gpu() const;
  void add_submission(const json& submission) const;

  TaskState state(const std::string& task) const;  // "pending" when there is no file yet
  void write_state(const std::string& task, const TaskState& s) const;

 private:
  std::filesystem::path dir_;
};

// <manifest folder>/<manifest stem>.batch
std::filesystem::path default_batch_folder(const std::filesystem::path& manifest);

// This program's own path (what tasks and job scripts run).
std::filesystem::path self_executable();

}  // namespace nf::batch
