#include "engine/batch/slurm_backend.hpp"

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/host.hpp"
#include "engine/core/text.hpp"

extern char** environ;

namespace nf::batch {

namespace fs = std::filesystem;

namespace {

// One of Slurm's clients run without a shell: its exit status (-1: it could not start, e.g. not
// installed), standard output and standard error (read together, so neither pipe can fill).
struct ClientRun {
  int status = -1;
  std::string out, err;
};

ClientRun run_client(const std::vector<std::string>& args) {
  ClientRun r;
  int out_pipe[2], err_pipe[2];
  if (pipe2(out_pipe, O_CLOEXEC) != 0) return r;
  if (pipe2(err_pipe, O_CLOEXEC) != 0) {
    close(out_pipe[0]), close(out_pipe[1]);
    return r;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out_pipe[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, err_pipe[1], STDERR_FILENO);
  std::vector<std::string> words = args;
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(out_pipe[1]), close(err_pipe[1]);
  if (spawned == 0) {
    pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
    std::string* into[2] = {&r.out, &r.err};
    for (int open_fds = 2; open_fds > 0;) {
      if (poll(fds, 2, -1) < 0) {
        if (errno == EINTR) continue;
        break;
      }
      for (int k = 0; k < 2; ++k) {
        if (fds[k].fd < 0 || !(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
        char buf[4096];
        const ssize_t n = read(fds[k].fd, buf, sizeof buf);
        if (n > 0) {
          into[k]->append(buf, std::size_t(n));
        } else if (n == 0 || errno != EINTR) {
          close(fds[k].fd);
          fds[k].fd = -1;
          --open_fds;
        }
      }
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  for (int fd : {out_pipe[0], err_pipe[0]})
    if (fd >= 0) close(fd);
  return r;
}

// "0-3" or "0,2,5": the --array list of these indices.
std::string array_list(const std::vector<std::size_t>& indices) {
  std::string out;
  std::size_t i = 0;
  while (i < indices.size()) {
    std::size_t j = i;
    while (j + 1 < indices.size() && indices[j + 1] == indices[j] + 1) ++j;
    if (!out.empty()) out += ',';
    out += std::to_string(indices[i]);
    if (j > i) out += "-" + std::to_string(indices[j]);
    i = j + 1;
  }
  return out;
}

}  // namespace

bool job_in_queue(const std::string& job) {
  if (job.empty()) return false;
  const ClientRun r = run_client({"squeue", "-h", "-o", "%i", "-j", job});
  return r.status == 0 && !r.out.empty();
}

std::string requeue_job(const std::string& job) {
  const ClientRun r = run_client({"scontrol", "requeue", job});
  if (r.status == -1) return "scontrol was not found";
  if (r.status != 0) return "scontrol requeue " + job + " failed: " + shorten(r.err, 300);
  return "";
}

std::vector<std::size_t> tasks_to_submit(const BatchFolder& folder, const std::vector<BatchTask>& tasks, bool rerun_done) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    const TaskState s = folder.state(tasks[i].name);
    if (s.state == "done" && !rerun_done) continue;
    // Still running or queued under an earlier submission: a second copy would only meet its lock.
    if ((s.state == "queued" || s.state == "running" || s.state == "requeued" || s.state == "stopped") && job_in_queue(s.job)) continue;
    out.push_back(i);
  }
  return out;
}

std::string sbatch_script(const fs::path& folder, const std::vector<BatchTask>& tasks, const fs::path& nf_gpu,
                          const std::vector<std::size_t>& indices, const SlurmOptions& o) {
  if (indices.empty()) return "";
  const fs::path dir = fs::absolute(folder);
  // #SBATCH lines take no quoting: a path with blanks would be cut there.
  if (dir.string().find_first_of(" \t\n") != std::string::npos)
    throw InputError("the batch folder '" + dir.string() + "' has a blank in its path, which #SBATCH --output cannot hold: choose another --out");
  std::ostringstream s;
  s << "#!/bin/bash\n";
  s << "# nf_gpu batch: one array task per scene (" << dir.string() << "/batch.json lists them by index)\n";
  s << "#SBATCH --job-name=" << (o.job_name.empty() ? "nf_gpu-" + dir.filename().string() : o.job_name) << "\n";
  s << "#SBATCH --array=" << array_list(indices);
  if (o.max_parallel > 0) s << "%" << o.max_parallel;
  s << "\n";
  s << "#SBATCH --requeue\n";
  // B: the batch shell, which execs nf_gpu: the stages get the signal and save their checkpoints.
  s << "#SBATCH --signal=B:TERM@" << o.signal_seconds << "\n";
  s << "#SBATCH --open-mode=append\n";
  s << "#SBATCH --output=" << (dir / "logs" / "slurm-%A_%a.out").string() << "\n";
  s << "#SBATCH --ntasks=1\n";
  if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
  if (!o.account.empty()) s << "#SBATCH --account=" << o.account << "\n";
  if (!o.time.empty()) s << "#SBATCH --time=" << o.time << "\n";
  if (!o.mem.empty()) s << "#SBATCH --mem=" << o.mem << "\n";
  if (o.gpus_per_task > 0) s << "#SBATCH --gres=gpu:" << o.gpus_per_task << "\n";
  if (o.cpus_per_task > 0) s << "#SBATCH --cpus-per-task=" << o.cpus_per_task << "\n";
  for (const std::string& e : o.extra) s << "#SBATCH " << e << "\n";
  s << "\n# the task's scene, by its array index\nnames=(";
  for (std::size_t i = 0; i < tasks.size(); ++i) s << (i ? " " : "") << shell_quote(tasks[i].name);
  s << ")\n";
  s << "exec " << shell_quote(nf_gpu.string()) << " batch task " << shell_quote(dir.string())
    << " --name=\"${names[$SLURM_ARRAY_TASK_ID]}\" --max-requeues " << o.max_requeues << "\n";
  return s.str();
}

std::string submit(const BatchFolder& folder, const std::string& script, const std::vector<BatchTask>& tasks,
                   const std::vector<std::size_t>& indices) {
  write_file_atomic(folder.sbatch_script(), script);
  // Filed as queued before sbatch returns: a task may start (and file itself running) at once.
  for (const std::size_t i : indices) {
    TaskState s = folder.state(tasks[i].name);
    s.state = "queued";
    s.job.clear();
    s.message.clear();
    folder.write_state(tasks[i].name, s);
  }
  // The job id is sbatch's standard output; its warnings go to standard error.
  const ClientRun r = run_client({"sbatch", "--parsable", folder.sbatch_script().string()});
  if (r.status == -1) throw InputError("sbatch was not found: is Slurm installed here?");
  std::string out = r.out;
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  if (r.status != 0)
    throw InputError("sbatch refused the job (" + folder.sbatch_script().string() + "): " + shorten(r.err.empty() ? out : r.err, 600));
  if (!r.err.empty()) std::fprintf(stderr, "%s", r.err.c_str());  // its warnings, for the user
  // --parsable prints "jobid" or "jobid;cluster".
  const std::string job = out.substr(0, out.find(';'));
  if (job.empty() || job.find_first_not_of("0123456789") != std::string::npos)
    throw InputError("sbatch answered '" + shorten(out, 200) + "' where a job id was expected");
  folder.add_submission({{"job", job}, {"tasks", indices.size()}, {"submitted", utc_now()}, {"host", host_name()}});
  for (const std::size_t i : indices) {
    TaskState s = folder.state(tasks[i].name);
    if (s.state != "queued") continue;  // started already
    s.job = job + "_" + std::to_string(i);
    folder.write_state(tasks[i].name, s);
  }
  return job;
}

}  // namespace nf::batch
