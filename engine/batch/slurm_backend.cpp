#include "engine/batch/slurm_backend.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/host.hpp"
#include "engine/core/text.hpp"

namespace nf::batch {

namespace fs = std::filesystem;

namespace {

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
  if (job.empty() || job.find_first_not_of("0123456789_") != std::string::npos) return false;
  FILE* pipe = popen(("squeue -h -o %i -j " + job + " 2>/dev/null").c_str(), "r");
  if (!pipe) return false;
  std::array<char, 128> buf{};
  const bool listed = std::fgets(buf.data(), int(buf.size()), pipe) != nullptr;
  pclose(pipe);
  return listed;
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
  // The job id is sbatch's standard output; its warnings and errors go to a file of their own.
  const fs::path errors = folder.dir() / "logs" / "sbatch.err";
  const std::string command = "sbatch --parsable " + shell_quote(folder.sbatch_script().string()) + " 2>" + shell_quote(errors.string());
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) throw InputError("cannot run sbatch: is Slurm installed here (`sbatch` on PATH)?");
  std::string out;
  std::array<char, 256> buf{};
  while (std::fgets(buf.data(), int(buf.size()), pipe)) out += buf.data();
  const int status = pclose(pipe);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  std::ifstream err_in(errors);
  const std::string said((std::istreambuf_iterator<char>(err_in)), std::istreambuf_iterator<char>());
  if (status != 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127) throw InputError("sbatch was not found: is Slurm installed here?");
    throw InputError("sbatch refused the job (" + folder.sbatch_script().string() + "): " + shorten(said.empty() ? out : said, 600));
  }
  // --parsable prints "jobid" or "jobid;cluster".
  const std::string job = out.substr(0, out.find(';'));
  if (job.empty() || job.find_first_not_of("0123456789") != std::string::npos)
    throw InputError("sbatch answered '" + shorten(out, 200) + "' where a job id was expected (" + errors.string() + ")");
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
