#include "engine/batch/task_run.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "engine/core/error.hpp"
#include "engine/core/host.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/core/log.hpp"
#include "engine/gpu/context.hpp"
#include "engine/pipeline/stages.hpp"

extern char** environ;

namespace nf::batch {

namespace fs = std::filesystem;

namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

// Appends this process's stdout and stderr to the task's log (every attempt in one file).
void redirect_output(const fs::path& log) {
  fs::create_directories(log.parent_path());
  const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError("cannot open the task's log '" + log.string() + "'");
  std::fflush(stdout);
  std::fflush(stderr);
  dup2(fd, STDOUT_FILENO);
  dup2(fd, STDERR_FILENO);
  close(fd);
}

// Runs `scontrol requeue JOB`; returns "" or what went wrong.
std::string requeue(const std::string& job) {
  std::vector<std::string> args{"scontrol", "requeue", job};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, "scontrol", nullptr, nullptr, argv.data(), environ) != 0) return "scontrol was not found";
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return "waiting for scontrol failed";
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return "scontrol requeue " + job + " failed (see the log)";
  return "";
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

int run_task(const BatchFolder& folder, const std::string& name, const TaskRunOptions& options) {
  const std::vector<BatchTask> tasks = folder.tasks();
  const auto it = std::find_if(tasks.begin(), tasks.end(), [&](const BatchTask& t) { return t.name == name; });
  if (it == tasks.end()) throw UsageError("the batch in '" + folder.dir().string() + "' has no task named '" + name + "'");
  const BatchTask& task = *it;
  if (options.log_to_file) redirect_output(folder.log_file(name));

  TaskState s = folder.state(name);
  s.state = "running";
  s.attempts += 1;
  s.host = host_name();
  s.pid = long(getpid());
  s.started = utc_now();
  s.ended.clear();
  s.job = slurm_job_of_this_process();
  s.message.clear();
  s.exit_code = 0;
  folder.write_state(name, s);
  std::printf("== %s: attempt %d of task '%s' on %s%s\n", s.started.c_str(), s.attempts, name.c_str(), s.host.c_str(),
              s.job.empty() ? "" : (" (Slurm job " + s.job + ")").c_str());
  std::fflush(stdout);

  install_interrupt_handler();
  int code = 0;
  std::string message;
  try {
    pipeline::ReconstructOptions o;
    o.scene = task.scene;
    o.work = task.work;
    o.quality = task.quality;
    o.settings = task.settings;
    if (task.scene_scale > 0) o.settings.push_back("knowledge.cm_per_unit=" + json(task.scene_scale).dump());
    gpu::Context context;
    const auto outcomes = pipeline::reconstruct(context, o);
    for (const auto& out : outcomes) std::printf("%-10s %s\n", out.name.c_str(), out.ran ? ("ran in " + std::to_string(out.seconds) + " s").c_str() : "unchanged, skipped");
  } catch (const Interrupted& e) {
    code = interrupted_exit_code();
    message = e.what();
  } catch (const Error& e) {
    code = int(e.code());
    message = e.what();
  } catch (const std::exception& e) {
    code = int(ExitCode::DeviceOrInternal);
    message = std::string("internal error: ") + e.what();
  }
  if (!message.empty()) std::fprintf(stderr, "nf_gpu: %s\n", message.c_str());

  const TaskVerdict v = verdict_of(code, message);
  s.state = v.state;
  s.exit_code = v.exit_code;
  s.message = v.message;
  s.ended = utc_now();
  if (v.retryable && !s.job.empty()) {
    // SLURM_RESTART_COUNT counts this job's requeues, whoever asked for them.
    const int restarts = std::atoi(env("SLURM_RESTART_COUNT").c_str());
    if (restarts >= options.max_requeues) {
      s.state = "failed";
      s.message += " (requeued " + std::to_string(restarts) + " times already: the limit, --max-requeues)";
    } else if (const std::string why = requeue(s.job); why.empty()) {
      s.state = "requeued";
    } else {
      // Slurm refuses when it is requeueing the job already (scontrol requeue, preemption): then
      // it runs again anyway.
      s.message += " (" + why + "; a job Slurm requeued itself runs again)";
    }
  }
  folder.write_state(name, s);
  std::printf("== %s: task '%s' %s%s\n", s.ended.c_str(), name.c_str(), s.state.c_str(),
              s.exit_code ? (" (exit " + std::to_string(s.exit_code) + ")").c_str() : "");
  std::fflush(stdout);
  return code;
}

}  // namespace nf::batch
