#pragma once
// `nf_gpu batch run --backend slurm`: one sbatch job array, a task per scene. Each array task execs
// `nf_gpu batch task` (so Slurm's batch-shell signal reaches the stages), is requeueable, and gets
// SIGTERM `signal_seconds` before its time limit, time enough to save a checkpoint; the task
// requeues itself when a rerun can finish it (task_run.hpp).
#include <string>
#include <vector>

#include "engine/batch/batch_folder.hpp"

namespace nf::batch {

struct SlurmOptions {
  std::string job_name;                        // "" = nf_gpu-<the batch folder's name>
  std::string partition, account, time, mem;  // "" = the cluster's default
  int gpus_per_task = 0;                      // --gres=gpu:N
  int cpus_per_task = 0;
  int max_parallel = 0;                       // %N on the array: tasks at once (0: no limit)
  int signal_seconds = 120;                   // SIGTERM this long before the time limit
  int max_requeues = 3;
  bool rerun_done = false;
  std::vector<std::string> extra;             // further #SBATCH lines, e.g. "--qos=low"
};

// The indices (into `tasks`) that are not done yet (all with rerun_done), leaving out those an
// earlier submission still has in the queue (squeue lists their job).
std::vector<std::size_t> tasks_to_submit(const BatchFolder& folder, const std::vector<BatchTask>& tasks, bool rerun_done);

// Whether squeue lists this job ("123" or "123_4").
bool job_in_queue(const std::string& job);

// `scontrol requeue JOB`: "" or what went wrong (Slurm's own words).
std::string requeue_job(const std::string& job);

// The job script running these indices of `tasks` from the batch folder `dir` with the binary
// `nf_gpu` (empty: nothing to submit). InputError for a folder whose path has a blank (#SBATCH lines
// cannot quote it).
std::string sbatch_script(const std::filesystem::path& dir, const std::vector<BatchTask>& tasks, const std::filesystem::path& nf_gpu,
                          const std::vector<std::size_t>& indices, const SlurmOptions& options);

// Writes the script, submits it with sbatch, records the job and files each submitted task as
// queued under it; returns the job id.
std::string submit(const BatchFolder& folder, const std::string& script, const std::vector<BatchTask>& tasks,
                   const std::vector<std::size_t>& indices);

}  // namespace nf::batch
