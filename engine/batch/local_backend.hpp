#pragma once
// `nf_gpu batch run --backend local`: the tasks on this machine, N at a time, each a separate
// `nf_gpu batch task` process in its own process group (so that Ctrl-C reaches each once, through
// this runner, and each saves its checkpoint). With several GPUs each slot has its own
// (NF_DEVICE); on a CPU driver the cores are shared out between the slots (LP_NUM_THREADS).
#include <string>
#include <vector>

#include "engine/batch/batch_folder.hpp"

namespace nf::batch {

struct LocalOptions {
  int jobs = 0;                        // tasks at once; 0: one per GPU, or 1 without GPUs
  std::vector<std::string> devices;    // NF_DEVICE per slot (empty: the default device for all)
  int cores = 0;                       // shared out between slots when no GPU is given (0: all)
  bool rerun_done = false;             // run tasks already done again (their cached stages skip)
  int max_requeues = 3;                // passed to the tasks (only Slurm uses it)
};

struct LocalSummary {
  int done = 0, failed = 0, stopped = 0, skipped = 0;
  int exit_code = 0;  // 0; 1 when a task failed or stopped; 130/143 when this runner was stopped
};

// The GPUs nf_gpu would use (discrete and integrated Vulkan devices), as NF_DEVICE indices.
std::vector<std::string> gpu_device_indices();

LocalSummary run_local(const BatchFolder& folder, const LocalOptions& options);

}  // namespace nf::batch
