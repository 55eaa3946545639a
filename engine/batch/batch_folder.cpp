#include "engine/batch/batch_folder.hpp"

#include <unistd.h>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/io/json_fields.hpp"

namespace nf::batch {

namespace fs = std::filesystem;

namespace {

json read_or_null(const fs::path& file) {
  if (!fs::exists(file)) return json();
  try {
    return io::read_json_file(file);
  } catch (const Error&) {
    return json();
  }
}

}  // namespace

void BatchFolder::write(const std::vector<BatchTask>& tasks, const fs::path& manifest, const fs::path& nf_gpu) const {
  fs::create_directories(dir_ / "tasks");
  fs::create_directories(dir_ / "logs");
  json j = json::object();
  if (fs::exists(record())) {
    j = read_or_null(record());
    // Its submissions are the only record of the jobs in the queue: never replaced unread.
    if (!j.is_object())
      throw InputError(record().string() + " is damaged (not a JSON object): move it away (its Slurm jobs: squeue) and run again");
  }
  j["version"] = 1;
  j["manifest"] = fs::absolute(manifest).string();
  j["nf_gpu"] = nf_gpu.string();
  j["tasks"] = json::array();
  for (const BatchTask& t : tasks) j["tasks"].push_back(to_json(t));
  if (!j.contains("submissions")) j["submissions"] = json::array();
  write_file_atomic(record(), dump_text(j, 2) + "\n");
}

json BatchFolder::read() const {
  if (!fs::exists(record()))
    throw InputError("'" + dir_.string() + "' is not a batch folder (no batch.json): run `nf_gpu batch run MANIFEST --out " +
                     dir_.string() + "` first");
  json j = io::read_json_file(record());
  if (!j.is_object() || !j.contains("tasks") || !j["tasks"].is_array())
    throw InputError(record().string() + ": not a batch record (no \"tasks\" list)");
  return j;
}

std::vector<BatchTask> BatchFolder::tasks() const {
  std::vector<BatchTask> out;
  const json j = read();
  try {
    for (const json& t : j["tasks"]) out.push_back(task_from_json(t));
  } catch (const json::exception& e) {
    throw InputError(record().string() + ": a task entry is broken (" + io::json_error_text(e) + "): rerun `nf_gpu batch run`");
  }
  return out;
}

fs::path BatchFolder::nf_gpu() const { return read().value("nf_gpu", self_executable().string()); }

void BatchFolder::add_submission(const json& submission) const {
  json j = read();
  j["submissions"].push_back(submission);
  write_file_atomic(record(), dump_text(j, 2) + "\n");
}

TaskState BatchFolder::state(const std::string& task) const {
  TaskState s;
  if (!fs::exists(state_file(task))) return s;
  const json j = read_or_null(state_file(task));
  if (!j.is_object()) {
    s.state = "unreadable";
    s.message = state_file(task).string() + " is damaged: run the task again to rewrite it";
    return s;
  }
  s.state = j.value("state", s.state);
  s.attempts = j.value("attempts", 0);
  s.host = j.value("host", std::string());
  s.pid = j.value("pid", 0L);
  s.started = j.value("started", std::string());
  s.ended = j.value("ended", std::string());
  s.job = j.value("job", std::string());
  s.message = j.value("message", std::string());
  s.exit_code = j.value("exit_code", 0);
  return s;
}

void BatchFolder::write_state(const std::string& task, const TaskState& s) const {
  const json j{{"state", s.state}, {"attempts", s.attempts}, {"host", s.host},   {"pid", s.pid},          {"started", s.started},
               {"ended", s.ended}, {"job", s.job},           {"message", s.message}, {"exit_code", s.exit_code}};
  write_file_atomic(state_file(task), dump_text(j, 2) + "\n");
}

fs::path default_batch_folder(const fs::path& manifest) {
  const fs::path m = fs::absolute(manifest);
  return m.parent_path() / (m.stem().string() + ".batch");
}

fs::path self_executable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw InternalError("cannot find this program's path (/proc/self/exe): " + ec.message());
  return p;
}

}  // namespace nf::batch
