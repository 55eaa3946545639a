#include "engine/batch/task_run.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cctype>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "engine/batch/local_backend.hpp"
#include "engine/batch/slurm_backend.hpp"
#include "engine/core/error.hpp"
#include "engine/core/host.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/gpu/context.hpp"
#include "engine/pipeline/stages.hpp"
#include "engine/pipeline/work_lock.hpp"


namespace nf::batch {

namespace fs = std::filesystem;

namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

std::string slurm_gpus_of_this_process() { return env("SLURM_JOB_GPUS").empty() ? env("SLURM_STEP_GPUS") : env("SLURM_JOB_GPUS"); }

// Appends this process's stdout and stderr to the task's log (every attempt in one file).
void redirect_output(const fs::path& log) {
  fs::create_directories(log.parent_path());
  const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError("cannot open the task's log '" + log.string() + "': " + std::strerror(errno));
  std::fflush(stdout);
  std::fflush(stderr);
  dup2(fd, STDOUT_FILENO);
  dup2(fd, STDERR_FILENO);
  close(fd);
}

// Under Slurm: the GPU and cores the job was given, for a task that was not told otherwise.
// Slurm numbers a node's GPUs as its gres.conf lists them, usually in PCI order, which is also the
// order in which Vulkan drivers list them; with device cgroups only the job's GPUs are visible and
// the default choice is right.
void take_slurm_resources() {
  const std::string gpus = slurm_gpus_of_this_process();
  if (env("NF_DEVICE").empty() && !gpus.empty())
    if (const std::string device = nf_device_for_slurm_gpus(gpus, gpu_device_indices()); !device.empty())
      setenv("NF_DEVICE", device.c_str(), 1);
  const std::string cpus = env("SLURM_CPUS_PER_TASK");
  if (!cpus.empty()) {
    if (env("NF_THREADS").empty()) setenv("NF_THREADS", cpus.c_str(), 1);
    if (env("LP_NUM_THREADS").empty()) setenv("LP_NUM_THREADS", cpus.c_str(), 1);
  }
}

}  // namespace

std::string slurm_job_of_this_process() {
  const std::string array = env("SLURM_ARRAY_JOB_ID"), index = env("SLURM_ARRAY_TASK_ID");
  if (!array.empty() && !index.empty()) return array + "_" + index;
  return env("SLURM_JOB_ID");
}

TaskVerdict verdict_of(int exit_code, const std::string& message) {
  TaskVerdict v;
  v.exit_code = exit_code;
  v.message = message;
  if (exit_code == 0) {
    v.state = "done";
  } else if (exit_code == int(ExitCode::BadInput) || exit_code == int(ExitCode::Usage)) {
    v.state = "failed";
  } else {
    v.state = "stopped";
    v.retryable = true;
  }
  return v;
}

bool may_requeue(int restarts, int max_requeues) { return restarts < max_requeues; }

std::string nf_device_for_slurm_gpus(const std::string& slurm_gpus, const std::vector<std::string>& visible) {
  if (slurm_gpus.empty() || !std::isdigit(static_cast<unsigned char>(slurm_gpus[0])) || visible.size() < 2) return "";
  const std::size_t first = std::strtoul(slurm_gpus.c_str(), nullptr, 10);
  return first < visible.size() ? visible[first] : "";
}

int run_task(const BatchFolder& folder, const std::string& name, const TaskRunOptions& options) {
  const std::vector<BatchTask> tasks = folder.tasks();
  const auto it = std::find_if(tasks.begin(), tasks.end(), [&](const BatchTask& t) { return t.name == name; });
  if (it == tasks.end()) throw UsageError("the batch in '" + folder.dir().string() + "' has no task named '" + name + "'");
  const BatchTask& task = *it;
  if (options.log_to_file) redirect_output(folder.log_file(name));
  const std::string job = slurm_job_of_this_process();
  if (!job.empty()) take_slurm_resources();

  // A live run holds this WORK (a copy of this task still running elsewhere): its state is its own.
  std::string busy;
  if (const json holder = pipeline::WorkLock::holder(task.work); holder.is_object() && pipeline::WorkLock::stale_reason(task.work, holder).empty())
    busy = "'" + task.work.string() + "' is in use by host " + holder.value("host", std::string("?")) + ", pid " +
           std::to_string(holder.value("pid", 0L));

  TaskState s = folder.state(name);
  const TaskState before = s;
  int code = 0;
  std::string message;
  install_interrupt_handler();
  if (busy.empty()) {
    s.state = "running";
    s.attempts += 1;
    s.host = host_name();
    s.pid = long(getpid());
    s.started = utc_now();
    s.ended.clear();
    s.job = job;
    s.message.clear();
    s.exit_code = 0;
    folder.write_state(name, s);
    const std::string gpus = slurm_gpus_of_this_process(), device = env("NF_DEVICE");
    std::printf("== %s: attempt %d of task '%s' on %s%s\n", s.started.c_str(), s.attempts, name.c_str(), s.host.c_str(),
                job.empty() ? ""
                            : (" (Slurm job " + job + (gpus.empty() ? "" : ", GPU " + gpus) +
                               (device.empty() ? "" : ", NF_DEVICE " + device) + ")").c_str());
    std::fflush(stdout);
    try {
      gpu::Context context;
      const auto outcomes = pipeline::reconstruct(context, reconstruct_options(task));
      for (const auto& out : outcomes)
        std::printf("%-10s %s\n", out.name.c_str(), out.ran ? ("ran in " + std::to_string(out.seconds) + " s").c_str() : "unchanged, skipped");
    } catch (const pipeline::WorkBusyError& e) {
      busy = e.what();  // lost the race for the lock after the check above
    } catch (const std::exception&) {
      const Failure f = current_failure();  // classified as `nf_gpu reconstruct` reports it
      code = f.exit_code;
      message = f.line();
    }
  }
  // From here on a signal must not cut the filing short: Slurm's own SIGTERM follows a requeue.
  std::signal(SIGTERM, SIG_IGN);
  std::signal(SIGINT, SIG_IGN);
  if (!busy.empty()) {
    code = kBusyExitCode;
    message = busy;
    s = before;  // the holder's state stays as it keeps it
  } else {
    const TaskVerdict v = verdict_of(code, message);
    s.state = v.state;
    s.exit_code = v.exit_code;
    s.message = v.message;
    s.ended = utc_now();
  }
  if (!message.empty()) std::fprintf(stderr, "nf_gpu: %s\n", message.c_str());

  const bool retryable = !busy.empty() || verdict_of(code, message).retryable;  // busy: try again later
  if (retryable && !job.empty()) {
    // SLURM_RESTART_COUNT counts this job's requeues, whoever asked for them.
    const int restarts = std::atoi(env("SLURM_RESTART_COUNT").c_str());
    if (!may_requeue(restarts, options.max_requeues)) {
      if (busy.empty()) {
        s.state = "failed";
        s.message += " (requeued " + std::to_string(restarts) + " times already: the limit, --max-requeues)";
      }
    } else {
      // Filed before asking: Slurm's SIGTERM may follow the request at once.
      const TaskState filed = s;
      if (busy.empty()) {
        s.state = "requeued";
        folder.write_state(name, s);
      }
      if (const std::string why = requeue_job(job); !why.empty()) {
        // Slurm refuses when it is requeueing the job already (scontrol requeue, preemption): then
        // it runs again anyway.
        s = filed;
        if (busy.empty()) s.message += " (" + why + "; a job Slurm requeued itself runs again)";
      }
    }
  }
  if (busy.empty()) folder.write_state(name, s);
  std::printf("== %s: task '%s' %s%s\n", utc_now().c_str(), name.c_str(), busy.empty() ? s.state.c_str() : "left to the run holding its WORK",
              code ? (" (exit " + std::to_string(code) + ")").c_str() : "");
  std::fflush(stdout);
  return code;
}

}  // namespace nf::batch
