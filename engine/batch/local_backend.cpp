#include "engine/batch/local_backend.hpp"

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <deque>
#include <map>
#include <thread>

#include "engine/batch/task_run.hpp"
#include "engine/core/error.hpp"
#include "engine/core/host.hpp"
#include "engine/gpu/context.hpp"

extern char** environ;

namespace nf::batch {

namespace {

constexpr int kMaxSlots = 256;
std::atomic<pid_t> g_children[kMaxSlots];
std::atomic<int> g_stop_signal{0};

// Forwards the first SIGINT or SIGTERM to every running task once (each saves its checkpoint);
// a second one ends the tasks at once.
extern "C" void forward_signal(int sig) {
  const int saved_errno = errno;
  const bool second = g_stop_signal.exchange(sig) != 0;
  for (auto& child : g_children) {
    const pid_t pid = child.load();
    if (pid > 0) kill(pid, second ? SIGKILL : sig);
  }
  errno = saved_errno;
}

// SIGINT and SIGTERM held back while a task is started and recorded, so none falls between.
class SignalsHeld {
 public:
  SignalsHeld() {
    sigemptyset(&set_);
    sigaddset(&set_, SIGINT);
    sigaddset(&set_, SIGTERM);
    sigprocmask(SIG_BLOCK, &set_, &old_);
  }
  ~SignalsHeld() { sigprocmask(SIG_SETMASK, &old_, nullptr); }
  SignalsHeld(const SignalsHeld&) = delete;
  SignalsHeld& operator=(const SignalsHeld&) = delete;

 private:
  sigset_t set_{}, old_{};
};

void install_forwarding() {
  struct sigaction action {};
  action.sa_handler = forward_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

pid_t spawn_task(const std::filesystem::path& exe, const BatchFolder& folder, const std::string& name, const LocalOptions& options,
                 const std::vector<std::pair<std::string, std::string>>& environment) {
  std::vector<std::string> args{exe.string(), "batch", "task", folder.dir().string(), "--name=" + name, "--max-requeues",
                                std::to_string(options.max_requeues)};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_text;
  for (char** e = environ; *e; ++e) {
    const std::string entry(*e);
    bool replaced = false;
    for (const auto& [key, value] : environment) replaced = replaced || entry.rfind(key + "=", 0) == 0;
    if (!replaced) env_text.push_back(entry);
  }
  for (const auto& [key, value] : environment) env_text.push_back(key + "=" + value);
  std::vector<char*> envp;
  for (std::string& e : env_text) envp.push_back(e.data());
  envp.push_back(nullptr);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  // Its own group: the terminal's Ctrl-C comes through us. Signals unblocked and at their defaults
  // in the child (the runner holds them back while it starts one).
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  posix_spawnattr_setpgroup(&attr, 0);
  sigset_t none, defaults;
  sigemptyset(&none);
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGINT);
  sigaddset(&defaults, SIGTERM);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  pid_t pid = 0;
  const int error = posix_spawn(&pid, exe.c_str(), nullptr, &attr, argv.data(), envp.data());
  posix_spawnattr_destroy(&attr);
  if (error != 0) throw InternalError("cannot start '" + exe.string() + "' for task '" + name + "': " + std::strerror(error));
  return pid;
}

}  // namespace

std::vector<std::string> gpu_device_indices() {
  std::vector<std::string> discrete, integrated;
  for (const auto& d : gpu::Context::enumerate_devices()) {
    if (d.type == "discrete") discrete.push_back(std::to_string(d.index));
    if (d.type == "integrated") integrated.push_back(std::to_string(d.index));
  }
  // A machine with discrete GPUs runs nothing on its integrated one (a fraction of the speed).
  return discrete.empty() ? integrated : discrete;
}

LocalSummary run_local(const BatchFolder& folder, const LocalOptions& options) {
  const std::vector<BatchTask> tasks = folder.tasks();
  const std::filesystem::path exe = folder.nf_gpu();
  LocalSummary summary;
  std::deque<std::string> queue;
  for (const BatchTask& t : tasks) {
    const TaskState s = folder.state(t.name);
    if (!options.rerun_done && s.state == "done") {
      ++summary.skipped;
      continue;
    }
    if (s.state == "running" && s.pid > 0 && s.host == host_name() && process_alive(pid_t(s.pid))) {
      std::printf("batch: '%s' is running already (pid %ld): left to it\n", t.name.c_str(), s.pid);
      ++summary.skipped;
      continue;
    }
    queue.push_back(t.name);
  }
  const int slots_wanted = options.jobs > 0 ? options.jobs : std::max<int>(1, int(options.devices.size()));
  const int slots = std::clamp(std::min<int>(slots_wanted, int(queue.size())), 1, kMaxSlots);
  const int cores = options.cores > 0 ? options.cores : int(std::max(1u, std::thread::hardware_concurrency()));
  std::printf("batch: %zu task(s) to run, %d at a time%s; %d already done\n", queue.size(), slots,
              options.devices.empty() ? "" : (", one GPU each (NF_DEVICE " + std::to_string(options.devices.size()) + " devices)").c_str(),
              summary.skipped);
  std::fflush(stdout);

  for (auto& c : g_children) c.store(0);
  g_stop_signal.store(0);
  install_forwarding();
  struct Started {
    int slot;
    std::string name;
    TaskState before;  // its state when started: a task that dies before filing leaves it as it was
  };
  std::map<pid_t, Started> running;
  // On an error here the tasks are stopped as Ctrl-C would, waited for, and the handlers restored.
  struct Cleanup {
    std::map<pid_t, Started>& running;
    ~Cleanup() {
      for (const auto& [pid, started] : running) kill(pid, SIGTERM);
      for (const auto& [pid, started] : running) {
        int status = 0;
        while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
        }
      }
      signal(SIGINT, SIG_DFL);
      signal(SIGTERM, SIG_DFL);
    }
  } cleanup{running};
  std::vector<bool> busy(std::size_t(slots), false);
  while (!queue.empty() || !running.empty()) {
    while (!queue.empty() && int(running.size()) < slots && g_stop_signal.load() == 0) {
      const int slot = int(std::find(busy.begin(), busy.end(), false) - busy.begin());
      std::vector<std::pair<std::string, std::string>> environment;
      if (!options.devices.empty()) {
        environment.emplace_back("NF_DEVICE", options.devices[std::size_t(slot) % options.devices.size()]);
      } else if (slots > 1) {
        // A CPU driver and the host work use every core by default: N tasks would oversubscribe
        // them N times.
        environment.emplace_back("LP_NUM_THREADS", std::to_string(std::max(1, cores / slots)));
        environment.emplace_back("NF_THREADS", std::to_string(std::max(1, cores / slots)));
      }
      const std::string name = queue.front();
      queue.pop_front();
      const SignalsHeld held;  // a signal now is forwarded once the task is recorded
      const TaskState before = folder.state(name);
      const pid_t pid = spawn_task(exe, folder, name, options, environment);
      g_children[slot].store(pid);
      busy[std::size_t(slot)] = true;
      running[pid] = {slot, name, before};
      std::printf("batch: started '%s' (pid %d%s)\n", name.c_str(), int(pid),
                  environment.empty() ? "" : (", " + environment[0].first + "=" + environment[0].second).c_str());
      std::fflush(stdout);
    }
    if (running.empty()) break;  // stopped before the queue emptied
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      throw InternalError(std::string("waiting for the batch's tasks failed: ") + std::strerror(errno));
    }
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const Started started = it->second;
    running.erase(it);
    g_children[started.slot].store(0);
    busy[std::size_t(started.slot)] = false;
    TaskState s = folder.state(started.name);
    const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    const bool filed_nothing = s.attempts == started.before.attempts && s.started == started.before.started;
    if (code == kBusyExitCode) {
      std::printf("batch: '%s' left to the run that holds its WORK (see its log)\n", started.name.c_str());
      ++summary.skipped;
      continue;
    }
    if ((s.state == "running" && s.pid == long(pid)) || (filed_nothing && code != 0)) {
      // Killed before it could file its state (SIGKILL, the kernel's out-of-memory killer), or it
      // never started.
      s.state = "stopped";
      s.exit_code = code;
      s.ended = utc_now();
      s.message = WIFSIGNALED(status) ? "killed by signal " + std::to_string(WTERMSIG(status)) + " (out of memory?); a rerun resumes"
                                      : "ended without filing its state (exit " + std::to_string(code) + "; see its log)";
      folder.write_state(started.name, s);
    }
    if (s.state == "done") ++summary.done;
    else if (s.state == "failed") ++summary.failed;
    else ++summary.stopped;
    std::printf("batch: '%s' %s (exit %d)%s%s\n", started.name.c_str(), s.state.c_str(), code, s.message.empty() ? "" : ": ",
                s.message.c_str());
    std::fflush(stdout);
  }
  const int sig = g_stop_signal.load();
  summary.stopped += int(queue.size());
  if (sig != 0) summary.exit_code = 128 + sig;
  else if (summary.failed + summary.stopped > 0) summary.exit_code = 1;
  return summary;
}

}  // namespace nf::batch
