#pragma once
// One batch task: `nf_gpu reconstruct` of one scene, run in this process (so that a SIGTERM from
// Slurm reaches the stages directly and they save their checkpoints), with its state file kept
// and, under Slurm, the job requeued when a rerun can finish it.
#include <string>
#include <vector>

#include "engine/batch/batch_folder.hpp"

namespace nf::batch {

struct TaskRunOptions {
  bool log_to_file = true;   // the task's output appended to logs/NAME.log (else the terminal's)
  int max_requeues = 3;      // Slurm: requeues a task may ask for itself before it is left failed
};

// The exit code of a task whose WORK another live run holds (EX_TEMPFAIL): its state file is left
// as that run keeps it, and under Slurm it is requeued to try later.
constexpr int kBusyExitCode = 75;

// How a finished attempt is filed: its state and whether a rerun can finish it.
struct TaskVerdict {
  std::string state;     // done, failed or stopped
  int exit_code = 0;
  bool retryable = false;
  std::string message;
};
// From the reconstruct's exit code: 0 done; 1 (bad input) and 2 (usage) failed, a rerun cannot fix
// them; 130/143 (stopped on a signal), 3 (device lost or out of memory), 75 (WORK busy) and deaths
// by a signal stopped, a rerun resumes.
TaskVerdict verdict_of(int exit_code, const std::string& message);

// Whether a retryable task under Slurm may requeue itself, having been requeued `restarts` times.
bool may_requeue(int restarts, int max_requeues);

// Runs the task, returns the process exit code (0 done; else the reconstruct's, or kBusyExitCode).
int run_task(const BatchFolder& folder, const std::string& name, const TaskRunOptions& options);

// The Slurm job of this process ("<array job>_<index>" or the job id), "" outside Slurm.
std::string slurm_job_of_this_process();

// The NF_DEVICE for the GPUs Slurm gave a job (SLURM_JOB_GPUS, e.g. "1" or "1,3": the node's GPU
// numbers in gres.conf's order) among the Vulkan devices a task may use (`visible`, in the
// driver's order): the first given GPU's device, or "" (the default device) when the list is not
// numbers, out of range, or only one device is visible (device cgroups hide the others).
std::string nf_device_for_slurm_gpus(const std::string& slurm_gpus, const std::vector<std::string>& visible);

}  // namespace nf::batch
