#include "engine/pipeline/pipeline.hpp"

#include <chrono>
#include <ctime>
#include <fstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/content_hash.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr int kRecordVersion = 1;

// Paths in keys are relative to the scene or WORK, so moving either folder keeps the cache valid.
std::string key_path(const fs::path& p, const StageContext& c) {
  const fs::path abs = fs::weakly_canonical(p);
  for (const auto& [root, tag] : {std::pair{c.work, "WORK"}, std::pair{c.scene_dir, "SCENE"}}) {
    const fs::path r = fs::weakly_canonical(root);
    const fs::path rel = abs.lexically_relative(r);
    if (!rel.empty() && *rel.begin() != "..") return std::string(tag) + "/" + rel.generic_string();
  }
  return abs.generic_string();
}

json stage_key(const Stage& stage, const StageContext& c) {
  json inputs = json::object();
  for (const fs::path& p : stage.inputs(c)) inputs[key_path(p, c)] = hash_file(p);
  return {{"version", kRecordVersion}, {"parameters", stage.parameters(c)}, {"inputs", inputs}};
}

json read_json(const fs::path& p) {
  std::ifstream in(p);
  try {
    return json::parse(in);
  } catch (const json::exception&) {
    return json();  // an unreadable record counts as absent: the stage runs again
  }
}

std::string now_utc() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

}  // namespace

fs::path stage_record(const fs::path& work, const std::string& stage) { return work / stage / "stage.json"; }

std::vector<StageOutcome> run_pipeline(const std::vector<std::unique_ptr<Stage>>& stages, StageContext& c,
                                       const RunOptions& options) {
  std::string names;
  bool from_found = options.from.empty(), to_found = options.to.empty();
  for (const auto& s : stages) {
    names += (names.empty() ? "" : ", ") + s->name();
    from_found |= s->name() == options.from;
    to_found |= s->name() == options.to;
  }
  if (!from_found) throw UsageError("--from: no stage named '" + options.from + "' (stages: " + names + ")");
  if (!to_found) throw UsageError("--to: no stage named '" + options.to + "' (stages: " + names + ")");
  fs::create_directories(c.work);

  std::vector<StageOutcome> outcomes;
  bool forced = false;
  for (const auto& stage : stages) {
    const std::string name = stage->name();
    forced |= name == options.from;
    const fs::path dir = c.work / name, record = stage_record(c.work, name);
    const fs::path partial = c.work / (name + ".partial"), old = c.work / (name + ".old");
    const fs::path resume = c.work / ".resume" / name;
    // A run killed in the middle of the swap below left no WORK/<name>: put back what it had.
    if (!fs::exists(dir)) {
      if (fs::exists(partial / "stage.json")) fs::rename(partial, dir);  // complete: the key decides below
      else if (fs::exists(old)) fs::rename(old, dir);
    }
    if (fs::exists(dir) && !fs::exists(record))
      throw InputError(dir.string() + " exists but holds no stage.json, so nf_gpu did not write it; move it away or "
                                      "choose another --out");
    const json key = stage_key(*stage, c);
    StageOutcome outcome;
    outcome.name = name;
    if (!forced && fs::exists(record)) {
      const json previous = read_json(record);
      if (previous.is_object() && previous.value("key", json()) == key) {
        outcome.summary = previous.value("summary", json::object());
        log::info("stage ", name, ": unchanged since ", previous.value("finished", std::string("?")), ", skipped");
        for (const fs::path& leftover : {partial, old, resume}) fs::remove_all(leftover);  // a kill's leftovers
        outcomes.push_back(outcome);
        if (name == options.to) break;
        continue;
      }
    }
    forced = true;  // a stage that reruns makes every later one rerun: their inputs may change

    fs::remove_all(partial);
    fs::create_directories(partial);
    if (fs::exists(resume / "key.json") && read_json(resume / "key.json") != key) {
      log::info("stage ", name, ": its inputs or settings changed since the checkpoint; starting afresh");
      fs::remove_all(resume);
    }
    fs::create_directories(resume);
    write_file_atomic(resume / "key.json", key.dump(2) + "\n");

    log::info("stage ", name, ": running");
    const auto start = std::chrono::steady_clock::now();
    outcome.summary = stage->run(c, partial, resume);
    outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    outcome.ran = true;
    write_file_atomic(partial / "stage.json", json{{"stage", name},
                                                   {"key", key},
                                                   {"summary", outcome.summary},
                                                   {"seconds", outcome.seconds},
                                                   {"finished", now_utc()}}
                                                  .dump(2) + "\n");
    // Swap: the previous result is removed only once the new one is complete.
    fs::remove_all(old);
    if (fs::exists(dir)) fs::rename(dir, old);
    fs::rename(partial, dir);
    fs::remove_all(old);
    fs::remove_all(resume);
    log::info("stage ", name, ": done in ", outcome.seconds, " s");
    outcomes.push_back(outcome);
    if (name == options.to) break;
  }
  return outcomes;
}

}  // namespace nf::pipeline
