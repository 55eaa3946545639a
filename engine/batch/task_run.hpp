#pragma once
// One batch task: `nf_gpu reconstruct` of one scene, run in this process (so that a SIGTERM from
// Slurm reaches the stages directly and they save their checkpoints), with its state file kept
// and, under Slurm, the job requeued when a rerun can finish it.
#include <string>

#include "engine/batch/batch_folder.hpp"

namespace nf::batch {

struct TaskRunOptions {
  bool log_to_file = true;   // the task's output appended to logs/NAME.log (else the terminal's)
  int max_requeues = 3;      // Slurm: requeues a task may ask for itself before it is left failed
};

// How a finished attempt is filed: its state and whether Slurm should run it again.
struct TaskVerdict {
  std::string state;     // done, failed or stopped
  int exit_code = 0;
  bool retryable = false;
  std::string message;
};
// From the reconstruct's exit code: 0 done; 1 (bad input) and 2 (usage) failed, a rerun cannot fix
// them; 130/143 (stopped on a signal) and 3 (device lost or out of memory) stopped, a rerun resumes.
TaskVerdict verdict_of(int exit_code, const std::string& message);

// Runs the task, returns the process exit code (0 done; else the reconstruct's).
int run_task(const BatchFolder& folder, const std::string& name, const TaskRunOptions& options);

// The Slurm job of this process ("<array job>_<index>" or the job id), "" outside Slurm.
std::string slurm_job_of_this_process();

}  // namespace nf::batch
