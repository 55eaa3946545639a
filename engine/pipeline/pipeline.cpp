#include "engine/pipeline/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <new>
#include <set>

#include "engine/core/atomic_file.hpp"
#include "engine/core/content_hash.hpp"
#include "engine/core/error.hpp"
#include "engine/core/host.hpp"
#include "engine/core/log.hpp"
#include "engine/core/output_guard.hpp"
#include "engine/core/text.hpp"
#include "engine/pipeline/stage_record.hpp"

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

// The settings that differ between two parameter objects, as "path before -> now" (objects are
// entered, so a nested setting is named by its dotted path).
void parameter_changes(const json& a, const json& b, const std::string& path, std::vector<std::string>& out) {
  if (a == b) return;
  if (a.is_object() && b.is_object()) {
    std::set<std::string> names;
    for (const auto& [k, v] : a.items()) names.insert(k);
    for (const auto& [k, v] : b.items()) names.insert(k);
    for (const std::string& k : names)
      parameter_changes(a.contains(k) ? a[k] : json(), b.contains(k) ? b[k] : json(), path.empty() ? k : path + "." + k, out);
    return;
  }
  const auto shown = [](const json& v) {
    const std::string text = v.is_null() ? "(none)" : dump_text(v);
    return text.size() > 40 ? text.substr(0, 37) + "..." : text;
  };
  out.push_back(path + " " + shown(a) + " -> " + shown(b));
}

// What differs between two keys, for people: "steps 400 -> 1200", "input WORK/body/fit.json".
std::vector<std::string> key_changes(const json& before, const json& now) {
  std::vector<std::string> out;
  if (before.value("version", 0) != now.value("version", 0)) out.push_back("the record's version");
  const json none = json::object();
  parameter_changes(before.contains("parameters") ? before["parameters"] : none, now.contains("parameters") ? now["parameters"] : none, "",
                    out);
  const json& i0 = before.contains("inputs") ? before["inputs"] : none;
  const json& i1 = now.contains("inputs") ? now["inputs"] : none;
  for (const auto& [k, v] : i1.items())
    if (!i0.contains(k) || i0[k] != v) out.push_back("input " + k);
  for (const auto& [k, v] : i0.items())
    if (!i1.contains(k)) out.push_back("input " + k + " (no longer read)");
  return out;
}

std::string first_changes(const std::vector<std::string>& changes) {
  std::vector<std::string> shown(changes.begin(), changes.begin() + std::ptrdiff_t(std::min<std::size_t>(4, changes.size())));
  return join(shown, "; ") + (changes.size() > shown.size() ? "; and " + std::to_string(changes.size() - shown.size()) + " more" : "");
}

// True when the stage's settings are all that differ from its result: the parameters it would have
// with the quality and settings that result was made with (recorded beside it) are its key's, and so
// are its inputs. Scene data in the parameters (cameras, the scene's unit) and the stage's version
// are then unchanged. False for a record that does not say what it was made with.
bool only_settings_differ(const Stage& stage, const StageContext& c, const StageRecord& previous, const json& key) {
  if (previous.quality.empty() || !previous.settings.is_object()) return false;
  if (previous.key.value("version", 0) != key.value("version", 0) ||
      previous.key.value("inputs", json::object()) != key.value("inputs", json::object()))
    return false;
  StageContext then = c;
  then.quality = previous.quality;
  then.settings[stage.name()] = previous.settings;
  try {
    return stage.parameters(then) == previous.key.value("parameters", json());
  } catch (const Error&) {  // a setting that no longer exists or is out of range now
    return false;
  }
}

// The advice for a stage that ran out of memory: its memory settings with their values.
std::string memory_advice(const Stage& stage, const StageContext& c) {
  const std::vector<std::string> keys = stage.memory_settings();
  if (keys.empty()) return "";
  json values;
  try {
    values = settings_values(stage.settings(), c);
  } catch (const Error&) {
    values = json::object();
  }
  // The same settings size the workgroup counts and binding ranges, so this serves every device limit.
  std::string advice = "; to ask less of the device, lower";
  for (std::size_t k = 0; k < keys.size(); ++k)
    advice += std::string(k ? "," : "") + " --set " + stage.name() + "." + keys[k] +
              (values.contains(keys[k]) ? " (now " + dump_text(values[keys[k]]) + ")" : "");
  return advice + (c.quality == "draft" ? "" : ", or use --quality draft");
}

// Called in a catch block: device and memory failures get the stage's name and what to do; other
// errors pass unchanged (they name their file or setting already).
[[noreturn]] void rethrow_with_stage(const Stage& stage, const StageContext& c) {
  const std::string where = "stage " + stage.name() + ": ";
  const std::string resume = "; its last checkpoint is kept: rerun the same command to resume";
  try {
    throw;
  } catch (const DeviceLostError& e) {
    throw DeviceLostError(where + e.what() + resume + " (after the driver has recovered, or on another device with NF_DEVICE)");
  } catch (const DeviceLimitError& e) {
    throw DeviceLimitError(where + e.what() + memory_advice(stage, c));
  } catch (const DeviceError& e) {
    throw DeviceError(where + e.what());
  } catch (const std::bad_alloc&) {
    throw DeviceError(where + "out of host memory" + memory_advice(stage, c));
  }
}

// The stages' declared graph: names, and for each the indices of the stages it reads.
struct StageGraph {
  std::vector<std::string> names;
  std::vector<std::vector<std::size_t>> deps;

  std::size_t index_of(const std::string& name, const std::string& option) const {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return i;
    throw UsageError(option + ": no stage named '" + name + "'" + did_you_mean(name, names) + " (stages: " +
                     join(names) + ")");
  }
  // `to` and everything it depends on; every stage when `to` is empty.
  std::set<std::size_t> needed_for(const std::string& to) const {
    std::set<std::size_t> out;
    if (to.empty()) {
      for (std::size_t i = 0; i < names.size(); ++i) out.insert(i);
      return out;
    }
    std::vector<std::size_t> todo{index_of(to, "--to")};
    while (!todo.empty()) {
      const std::size_t i = todo.back();
      todo.pop_back();
      if (out.insert(i).second) todo.insert(todo.end(), deps[i].begin(), deps[i].end());
    }
    return out;
  }
  // `from` and every stage that depends on it, directly or not; none when `from` is empty.
  std::set<std::size_t> forced_by(const std::string& from) const {
    std::set<std::size_t> out;
    if (from.empty()) return out;
    out.insert(index_of(from, "--from"));
    for (std::size_t i = 0; i < names.size(); ++i)  // stages are listed after what they read
      for (const std::size_t d : deps[i])
        if (out.count(d)) out.insert(i);
    return out;
  }
};

StageGraph stage_graph(const std::vector<std::unique_ptr<Stage>>& stages) {
  StageGraph g;
  for (const auto& s : stages) {
    std::vector<std::size_t> deps;
    for (const std::string& d : s->depends_on()) {
      const auto it = std::find(g.names.begin(), g.names.end(), d);
      NF_CHECK(it != g.names.end(), "stage " + s->name() + " depends on '" + d + "', which is not listed before it");
      deps.push_back(std::size_t(it - g.names.begin()));
    }
    g.names.push_back(s->name());
    g.deps.push_back(std::move(deps));
  }
  return g;
}

// An input that is missing: under WORK/<stage>/ it is that stage's output, so say to run it.
void require_inputs(const Stage& stage, const StageContext& c, const StageGraph& graph) {
  for (const fs::path& p : stage.inputs(c)) {
    if (fs::exists(p)) continue;
    const fs::path rel = fs::weakly_canonical(p).lexically_relative(fs::weakly_canonical(c.work));
    if (!rel.empty() && *rel.begin() != "..") {
      const std::string owner = rel.begin()->string();
      if (std::find(graph.names.begin(), graph.names.end(), owner) != graph.names.end())
        throw InputError("stage " + stage.name() + " needs " + p.string() + ", which is missing: rerun stage " + owner +
                         " (nf_gpu reconstruct ... --from " + owner + ")");
    }
    throw InputError("stage " + stage.name() + " needs " + p.string() + ", which is missing");
  }
}

}  // namespace

std::vector<std::string> stages_needed(const std::vector<std::unique_ptr<Stage>>& stages, const std::string& to) {
  const StageGraph graph = stage_graph(stages);
  std::vector<std::string> names;
  for (const std::size_t i : graph.needed_for(to)) names.push_back(graph.names[i]);
  return names;
}

fs::path stage_record(const fs::path& work, const std::string& stage) { return work / stage / "stage.json"; }

std::vector<StageOutcome> run_pipeline(const std::vector<std::unique_ptr<Stage>>& stages, StageContext& c,
                                       const RunOptions& options) {
  const StageGraph graph = stage_graph(stages);
  const std::set<std::size_t> needed = graph.needed_for(options.to);
  const std::set<std::size_t> forced = graph.forced_by(options.from);
  if (!options.from.empty() && !needed.count(graph.index_of(options.from, "--from")))
    throw UsageError("--from " + options.from + ": stage " + options.to + " (--to) does not depend on it");
  create_output_folder(c.work, "--out");

  std::vector<StageOutcome> outcomes;
  std::set<std::string> ran;
  for (std::size_t i = 0; i < stages.size(); ++i) {
    if (!needed.count(i)) continue;
    const Stage& stage = *stages[i];
    const std::string name = stage.name();
    bool force = forced.count(i) > 0;
    for (const std::string& d : stage.depends_on()) force |= ran.count(d) > 0;  // its inputs were remade
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
    require_inputs(stage, c, graph);
    const json key = stage_key(stage, c);
    StageOutcome outcome;
    outcome.name = name;
    if (!force && fs::exists(record)) {
      const std::optional<StageRecord> previous = read_stage_record(record);
      if (previous && previous->key == key) {
        outcome.summary = previous->summary;
        log::info("stage ", name, ": unchanged since ", previous->finished, ", skipped");
        for (const fs::path& leftover : {partial, old, resume}) fs::remove_all(leftover);  // a kill's leftovers
        outcomes.push_back(outcome);
        continue;
      }
      if (previous) {
        const std::vector<std::string> changes = key_changes(previous->key, key);
        // Minutes of work are not thrown away for a stage the user neither named (--set, or
        // another --quality) nor asked for (--to a later stage) when only its settings differ (the
        // defaults of another quality, or --set values of an earlier run).
        const bool upstream = !options.to.empty() && graph.index_of(options.to, "--to") != i;
        const bool named = c.settings.contains(name) || (options.quality_named && previous->quality != c.quality);
        if (upstream && !named && only_settings_differ(stage, c, *previous, key)) {
          outcome.summary = previous->summary;
          outcome.kept = "its result was made with other settings (" + first_changes(changes) + "); kept, as this run asks for " +
                         options.to + " and sets none of " + name + "'s settings: --from " + name + " remakes it";
          log::warn("stage ", name, ": ", outcome.kept);
          // A checkpoint in `resume` may be this run's settings' own (an interrupted --from): kept.
          for (const fs::path& leftover : {partial, old}) fs::remove_all(leftover);
          outcomes.push_back(outcome);
          continue;
        }
        log::info("stage ", name, ": runs again, what it was made from changed: ", first_changes(changes));
      }
    }

    fs::remove_all(partial);
    fs::create_directories(partial);
    if (fs::exists(resume / "key.json") && read_json_or_null(resume / "key.json") != key) {
      log::info("stage ", name, ": its inputs or settings changed since the checkpoint; starting afresh");
      fs::remove_all(resume);
    }
    fs::create_directories(resume);
    write_file_atomic(resume / "key.json", dump_text(key, 2) + "\n");

    log::info("stage ", name, ": running", fs::exists(record) ? "" : " (no result yet)");
    const auto start = std::chrono::steady_clock::now();
    try {
      outcome.summary = stages[i]->run(c, partial, resume);
    } catch (...) {
      fs::remove_all(partial);  // half an output is no output; the checkpoint in `resume` stays
      rethrow_with_stage(stage, c);
    }
    outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    outcome.ran = true;
    write_file_atomic(partial / "stage.json", dump_text(json{{"stage", name},
                                                             {"key", key},
                                                             {"quality", c.quality},
                                                             {"settings", settings_values(stage.settings(), c)},
                                                             {"summary", outcome.summary},
                                                             {"seconds", outcome.seconds},
                                                             {"finished", utc_now()}},
                                                        2) + "\n");
    // Swap: the previous result is removed only once the new one is complete, and on disk (a
    // file server may otherwise commit the renames before the data they name).
    if (const int error = sync_tree(partial)) {
      fs::remove_all(partial);
      throw InputError("stage " + name + ": its outputs in '" + partial.string() + "' could not be written to disk: " +
                       std::strerror(error) + " (the earlier result is kept; free space or fix the disk, then run again)");
    }
    fs::remove_all(old);
    if (fs::exists(dir)) fs::rename(dir, old);
    fs::rename(partial, dir);
    (void)sync_folder(c.work);
    fs::remove_all(old);
    fs::remove_all(resume);
    log::info("stage ", name, ": done in ", outcome.seconds, " s");
    outcomes.push_back(outcome);
    ran.insert(name);
  }
  return outcomes;
}

}  // namespace nf::pipeline
