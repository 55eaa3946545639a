// `nf_gpu batch` end to end on tiny synthetic scenes (and, under Slurm, one whose scene file is
// broken: it fails once and is not requeued):
// - local: two scenes two at a time, the runner stopped with SIGTERM in their fur stages, then run
//   again: each resumes from its checkpoint and ends like the same scene run with `reconstruct`;
//   status, the reports, and the WORK lock refusing a second run;
// - Slurm: a real two-node cluster (tests/batch/slurm_cluster.sh: munged, slurmctld and a slurmd
//   per node of Debian's packages, each node under a host name of its own) runs the scenes as a
//   job array, a task per node; one task is requeued with `scontrol requeue` and one is sent
//   SIGTERM in its fur stage; then the node running the first task, resumed, is crashed (every
//   process of it killed at once): Slurm finds the node down and requeues the task, which resumes
//   on the other node and takes its WORK lock over from the dead host. All finish, resumed from
//   their checkpoints, and write what reconstruct writes (with 4 scenes, the first is compared
//   with the same scene run by `reconstruct`).
//   NF_SLURM_SCENES sets how many scenes (default 2; the `long` entry runs 4).
#include <doctest/doctest.h>

#include <chrono>
#include <cstdlib>
#include <regex>
#include <map>
#include <set>

#include "engine/core/json.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/io/strand_files.hpp"
#include "tests/support/nf_process.hpp"

namespace fs = std::filesystem;
using nf::json;
using namespace nf::test;

namespace {

// The stages at their smallest (as the kill-and-resume test runs them).
const json kTinySettings = {
    {"neus.steps", 80},           {"neus.checkpoint_interval", 10}, {"neus.rays", 128},          {"neus.samples_per_ray", 16},
    {"neus.fine_samples", 8},     {"neus.hull_fit_steps", 5},       {"neus.mesh_resolution", 48}, {"neus.hull_resolution", 48},
    {"body.samples", 2000},       {"body.hypothesis_steps", 8},     {"body.global_steps", 10},    {"body.pose_steps", 20},
    {"body.offset_steps", 10},    {"body.preview_views", 1},        {"defur.resolution", 64},     {"defur.preview_views", 1},
    {"frames.roots", 3000},       {"fur.steps", 60},                {"fur.warm_steps", 4},        {"fur.batch", 400},
    {"fur.checkpoint_interval", 5}, {"fur.resolved_fur_px", 0},     {"fur.strands", 2500},        {"fur.metric_strands", 300},
    {"fur.resolution", 64},       {"fur.preview_views", 1},         {"fur.chamfer_queries", 500}, {"export.turntable_frames", 2},
    {"export.compare_views", 1}};

struct Scene {
  std::string name, animal;
  int seed;
};

std::vector<Scene> make_scenes(const fs::path& root, int count) {
  const std::vector<Scene> all{{"cat", "cat", 1}, {"dog", "dog", 1}, {"cat2", "cat", 2}, {"dog2", "dog", 2}};
  std::vector<Scene> scenes(all.begin(), all.begin() + count);
  for (const Scene& s : scenes) {
    const Result r = run("synth --animal " + s.animal + " --seed " + std::to_string(s.seed) + " --views 8 --res 64 --strands 4000 --spp-axis 1 --out " +
                         (root / "scenes" / s.name).string());
    REQUIRE_MESSAGE(r.code == 0, r.output);
  }
  return scenes;
}

// `broken`: one more scene whose transforms.json is not JSON, which only its task finds out.
void write_manifest(const fs::path& file, const std::vector<Scene>& scenes, bool broken = false) {
  json list = json::array();
  for (const Scene& s : scenes)
    list.push_back({{"scene", "scenes/" + s.name}, {"work", "work/" + s.name}, {"settings", {{"knowledge.preset", s.animal}}}});
  if (broken) {
    fs::create_directories(file.parent_path() / "scenes" / "broken");
    spit(file.parent_path() / "scenes" / "broken" / "transforms.json", "{\"frames\": [");
    list.push_back({{"scene", "scenes/broken"}, {"work", "work/broken"}, {"settings", {{"knowledge.preset", "cat"}}}});
  }
  spit(file, json{{"defaults", {{"quality", "draft"}, {"settings", kTinySettings}}}, {"scenes", list}}.dump(2));
}

// The same scene through `reconstruct`, for comparison.
void reconstruct_reference(const fs::path& scene, const std::string& animal, const fs::path& out) {
  std::string args = "reconstruct --scene " + scene.string() + " --out " + out.string() + " --quality draft --set knowledge.preset=" + animal;
  for (const auto& [key, value] : kTinySettings.items()) args += " --set " + key + "=" + value.dump();
  const Result r = run(args);
  REQUIRE_MESSAGE(r.code == 0, r.output);
}

std::set<std::string> file_names(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) names.insert(fs::relative(e.path(), dir).string());
  return names;
}

json stage_summary(const fs::path& work, const std::string& stage) {
  return json::parse(slurp(work / stage / "stage.json"))["summary"];
}

// A batch task's output against the scene run directly: the same files in every stage folder, the
// same strand count and steps, scores within the spread two uninterrupted runs show (the
// kill-and-resume test's tolerances).
void check_like_reference(const fs::path& work, const fs::path& reference) {
  for (const std::string& stage : stage_names()) {
    INFO(stage);
    CHECK(file_names(work / stage) == file_names(reference / stage));
  }
  CHECK(nf::io::read_hair(work / "export" / "fur.hair").strand_count() ==
        nf::io::read_hair(reference / "export" / "fur.hair").strand_count());
  CHECK(stage_summary(work, "neus")["ground_truth"]["chamfer_mean_pct_diagonal"].get<double>() < 6.0);
  const json fa = stage_summary(work, "fur"), fb = stage_summary(reference, "fur");
  CHECK(fa["steps"] == fb["steps"]);
  CHECK(std::abs(fa["held_out"]["silhouette_iou"].get<double>() - fb["held_out"]["silhouette_iou"].get<double>()) < 0.15);
  CHECK_FALSE(fs::exists(work / ".lock"));
  if (fs::exists(work / ".resume")) CHECK(file_names(work / ".resume").empty());  // checkpoints go once their stage is done
}

json status_of(const fs::path& batch, const std::string& env = "") {
  const Result r = run("batch status " + batch.string() + " --json", env);
  REQUIRE_MESSAGE(r.code == 0, r.output);
  return json_of(r);
}

// A shell command's output (for the Slurm clients).
std::string shell(const std::string& command) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  REQUIRE(pipe != nullptr);
  std::string out;
  char buffer[4096];
  while (std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) out.append(buffer, n);
  pclose(pipe);
  return out;
}

}  // namespace

TEST_CASE("batch, local backend: two scenes at a time, stopped with SIGTERM in their fur stages, resumed, like reconstruct") {
  const fs::path root = fs::temp_directory_path() / "nf_batch_local";
  fs::remove_all(root);
  const auto scenes = make_scenes(root, 2);
  write_manifest(root / "m.json", scenes);
  const fs::path batch = root / "m.batch";

  const fs::path log = root / "run1.txt";
  const pid_t runner = spawn("batch run " + (root / "m.json").string() + " --jobs 2", log);
  for (const Scene& s : scenes) REQUIRE_MESSAGE(wait_for(batch / "logs" / (s.name + ".log"), "stage fur: running", 240), slurp(log));
  std::this_thread::sleep_for(std::chrono::seconds(2));  // a few fur steps, so there is a checkpoint to resume
  kill(runner, SIGTERM);
  CHECK(wait_exit(runner) == 143);
  const std::string stopped = slurp(log);
  INFO(stopped);
  for (const Scene& s : scenes) {
    const json state = json::parse(slurp(batch / "tasks" / (s.name + ".json")));
    CHECK(state["state"] == "stopped");
    CHECK(state["exit_code"] == 143);
    CHECK(state["message"].get<std::string>().find("checkpoint saved") != std::string::npos);
    CHECK_FALSE(fs::exists(root / "work" / s.name / ".lock"));  // released on the way out
  }

  const Result again = run("batch run " + (root / "m.json").string() + " --jobs 2");
  REQUIRE_MESSAGE(again.code == 0, again.output);
  CHECK(again.output.find("2 scene(s): 2 done") != std::string::npos);
  for (const Scene& s : scenes) {
    const std::string resumed = slurp(batch / "logs" / (s.name + ".log"));
    CHECK(resumed.find("fur: resuming from") != std::string::npos);
    // The views the stopped run made are read back, not made again from the photos.
    CHECK_MESSAGE(resumed.find("views' targets read back from the interrupted run") != std::string::npos, resumed);
  }
  for (const json& row : status_of(batch)) {
    CHECK(row["state"] == "done");
    CHECK(row["attempts"] == 2);
    CHECK(row["stage_reached"] == "export");
    CHECK(row["scores"].contains("fur_F_2cm"));
  }
  // Done scenes are not run again.
  const Result third = run("batch run " + (root / "m.json").string());
  CHECK(third.code == 0);
  CHECK(third.output.find("0 task(s) to run") != std::string::npos);

  reconstruct_reference(root / "scenes" / "cat", "cat", root / "reference");
  check_like_reference(root / "work" / "cat", root / "reference");

  // The report: a page whose every image exists.
  const Result report = run("batch report " + batch.string());
  REQUIRE_MESSAGE(report.code == 0, report.output);
  const std::string html = slurp(batch / "report.html");
  const std::regex img("<img src=\"([^\"]+)\"");
  int images = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), img); it != std::sregex_iterator(); ++it, ++images)
    CHECK_MESSAGE(fs::exists(batch / (*it)[1].str()), (*it)[1].str());
  CHECK(images >= 2);
  CHECK(slurp(batch / "report.md").find("| cat | done | 2 | export |") != std::string::npos);

  // One run per WORK folder: a second reconstruct into a WORK in use is refused and changes nothing.
  const fs::path busy_log = root / "busy.txt";
  const pid_t first = spawn("reconstruct --scene " + (root / "scenes" / "dog").string() + " --out " + (root / "busy").string() +
                                " --quality draft --set knowledge.preset=dog",
                            busy_log);
  REQUIRE(wait_for(busy_log, "stage neus: running", 60));
  const Result second = run("reconstruct --scene " + (root / "scenes" / "dog").string() + " --out " + (root / "busy").string() +
                            " --quality draft --set knowledge.preset=dog");
  CHECK(second.code == 1);
  CHECK(second.output.find("is in use by another nf_gpu run") != std::string::npos);
  CHECK(second.output.find("pid " + std::to_string(first)) != std::string::npos);
  kill(first, SIGTERM);
  CHECK(wait_exit(first) == 143);
  CHECK_FALSE(fs::exists(root / "busy" / ".lock"));
  fs::remove_all(root);
}

TEST_CASE("batch, Slurm backend: a job array on a real two-node cluster, one task requeued, one sent SIGTERM and one node crashed mid-fur") {
  const int count = std::getenv("NF_SLURM_SCENES") ? std::atoi(std::getenv("NF_SLURM_SCENES")) : 2;
  REQUIRE((count >= 2 && count <= 4));
  const fs::path root = fs::temp_directory_path() / ("nf_batch_slurm_" + std::to_string(count));
  fs::remove_all(root);
  const fs::path cluster = root / "cluster";
  const std::string started = shell(std::string(NF_SLURM_CLUSTER_SCRIPT) + " start " + cluster.string() + " 2");
  REQUIRE_MESSAGE(fs::exists(cluster / "slurm.conf"), started);
  // A lock another host has not refreshed for 15 s is taken over (300 s on a cluster): the crashed
  // node's task leaves one behind.
  const std::string env = "SLURM_CONF=" + (cluster / "slurm.conf").string() + " NF_WORK_LOCK_STALE_S=15";
  struct StopCluster {
    fs::path dir;
    ~StopCluster() { std::system((std::string(NF_SLURM_CLUSTER_SCRIPT) + " stop " + dir.string() + " >/dev/null 2>&1").c_str()); }
  } stop_cluster{cluster};

  const auto scenes = make_scenes(root, count);
  write_manifest(root / "m.json", scenes, true);
  const fs::path batch = root / "m.batch";
  const nf::Stopwatch t0;
  std::string timeline;
  const auto mark = [&](const std::string& what) {
    char line[256];
    std::snprintf(line, sizeof line, "%7.1f s  %s\n", t0.seconds(), what.c_str());
    timeline += line;
  };

  const Result submitted = run("batch run " + (root / "m.json").string() + " --backend slurm --max-parallel 2 --cpus-per-task 1 --gpus-per-task 1", env);
  REQUIRE_MESSAGE(submitted.code == 0, submitted.output);
  std::smatch m;
  REQUIRE_MESSAGE(std::regex_search(submitted.output, m, std::regex("submitted job array ([0-9]+)")), submitted.output);
  const std::string job = m[1].str();
  mark("submitted job array " + job + " (" + std::to_string(count) + " scenes, 2 at a time)");
  CHECK(slurp(batch / "batch.sbatch").find("#SBATCH --requeue") != std::string::npos);
  CHECK(slurp(batch / "batch.sbatch").find("#SBATCH --gres=gpu:1") != std::string::npos);
  // Submitted, so a second submission leaves them alone while they are queued or running.
  const Result resubmitted = run("batch run " + (root / "m.json").string() + " --backend slurm --max-parallel 2 --cpus-per-task 1 --gpus-per-task 1", env);
  CHECK(resubmitted.code == 0);
  CHECK(resubmitted.output.find("nothing submitted") != std::string::npos);

  for (int i = 0; i < 2; ++i)
    REQUIRE_MESSAGE(wait_for(batch / "logs" / (scenes[std::size_t(i)].name + ".log"), "stage fur: running", 300),
                    (shell(env + " squeue") + slurp(batch / "logs" / (scenes[std::size_t(i)].name + ".log"))));
  std::this_thread::sleep_for(std::chrono::seconds(2));  // a few fur steps, so there is a checkpoint to resume
  CHECK(shell(env + " scontrol requeue " + job + "_0").find("error") == std::string::npos);
  mark("scontrol requeue " + job + "_0 (" + scenes[0].name + ", in its fur stage)");
  // scancel may retry for a minute and more when the job requeues itself meanwhile (the task's own
  // `scontrol requeue`); the signal is sent at once, so it is given 15 s, and judged by its effect.
  const std::string cancelled = shell(env + " timeout 15 scancel --batch --signal=TERM " + job + "_1");
  mark("scancel --batch --signal=TERM " + job + "_1 (" + scenes[1].name + ", in its fur stage)" +
       (cancelled.empty() ? "" : ": " + cancelled.substr(0, cancelled.find('\n'))));

  // Slurm holds a requeued job for two minutes before it may start again; the test releases them,
  // 10 s on: a requeued task released at once was started while its last run was still being torn
  // down, and Slurm killed it ("Job credential revoked") with nothing left to requeue it.
  // Once the first task has resumed, the node running it is crashed: Slurm finds it down (6 s
  // without an answer, the cluster's SlurmdTimeout) and requeues the task, which can only run on
  // the other node now.
  bool all_done = false;
  std::set<std::string> resumed;
  std::map<std::string, double> released;  // job id -> when it was last released (t0's seconds)
  std::string crashed_node;
  bool down_seen = false, resumed_after_crash = false;
  const auto hosts_of = [&](const std::string& name) {  // the host of each attempt, from the task's log
    std::vector<std::string> hosts;
    const std::string log = slurp(batch / "logs" / (name + ".log"));
    const std::regex attempt("attempt [0-9]+ of task '" + name + "' on ([A-Za-z0-9._-]+)");
    for (auto it = std::sregex_iterator(log.begin(), log.end(), attempt); it != std::sregex_iterator(); ++it) hosts.push_back((*it)[1].str());
    return hosts;
  };
  const auto occurrences = [&](const std::string& name, const std::string& text) {  // in the task's log
    const std::string log = slurp(batch / "logs" / (name + ".log"));
    std::size_t n = 0;
    for (std::size_t at = log.find(text); at != std::string::npos; at = log.find(text, at + 1)) ++n;
    return n;
  };
  const auto resumes_of = [&](const std::string& name) { return occurrences(name, "fur: resuming from"); };
  while (!all_done && t0.seconds() < 600) {
    std::this_thread::sleep_for(std::chrono::seconds(2));
    const std::string pending = shell(env + " squeue -h -t PD -r -o '%i %r'");
    std::istringstream lines(pending);
    for (std::string id, reason; lines >> id >> reason;)
      if (reason == "BeginTime" && (!released.count(id) || t0.seconds() > released[id] + 20)) {
        (void)shell(env + " scontrol update JobId=" + id + " StartTime=now+10");
        released[id] = t0.seconds();
      }
    for (const Scene& s : scenes)
      if (!resumed.count(s.name) && resumes_of(s.name) >= 1) {
        resumed.insert(s.name);
        const auto hosts = hosts_of(s.name);
        mark(s.name + " resumed from its fur checkpoint on " + (hosts.empty() ? "?" : hosts.back()));
        if (s.name == scenes[0].name && !hosts.empty()) {
          crashed_node = hosts.back();
          const std::string crash = shell(std::string(NF_SLURM_CLUSTER_SCRIPT) + " crash " + cluster.string() + " " + crashed_node);
          REQUIRE_MESSAGE(crash.empty(), crash);
          mark("node " + crashed_node + " crashed (its slurmd, job step and task killed)");
        }
      }
    if (!crashed_node.empty() && !down_seen &&
        shell(env + " sinfo -h -n " + crashed_node + " -o %T").find("down") != std::string::npos) {
      down_seen = true;
      mark("Slurm finds node " + crashed_node + " down");
    }
    if (!crashed_node.empty() && !resumed_after_crash && resumes_of(scenes[0].name) >= 2) {
      resumed_after_crash = true;
      const auto hosts = hosts_of(scenes[0].name);
      mark(scenes[0].name + " resumed from its fur checkpoint on " + (hosts.empty() ? "?" : hosts.back()));
    }
    all_done = true;
    for (const json& row : status_of(batch, env)) all_done = all_done && (row["state"] == "done" || row["name"] == "broken");
    all_done = all_done && shell(env + " squeue -h").empty();
  }
  mark("all done");
  MESSAGE("Slurm timeline:\n", timeline);
  REQUIRE_MESSAGE(all_done, (shell(env + " squeue") + shell("tail -n 30 " + (cluster / "log" / "slurmctld.log").string())));
  const json rows = status_of(batch, env);
  REQUIRE(rows.size() == scenes.size() + 1);
  CHECK(rows[0]["attempts"] == 3);
  CHECK(rows[1]["attempts"] == 2);
  for (std::size_t i = 2; i < scenes.size(); ++i) CHECK(rows[i]["attempts"] == 1);
  // Bad input fails once and is not requeued.
  const json& broken = rows[scenes.size()];
  CHECK(broken["state"] == "failed");
  CHECK(broken["attempts"] == 1);
  CHECK(slurp(batch / "logs" / "broken.log").find("not valid JSON") != std::string::npos);
  // The task Slurm requeued was stopped by Slurm's SIGTERM, then finished.
  const std::string log0 = slurp(batch / "logs" / (scenes[0].name + ".log"));
  CHECK(log0.find("task '" + scenes[0].name + "' stopped") != std::string::npos);
  CHECK(log0.find("task '" + scenes[0].name + "' done") != std::string::npos);
  CHECK(resumed.count(scenes[0].name) == 1);
  CHECK(resumed.count(scenes[1].name) == 1);
  // The task sent SIGTERM asked Slurm to requeue it; the one requeued by scontrol was stopped by Slurm.
  const std::string log1 = slurp(batch / "logs" / (scenes[1].name + ".log"));
  CHECK(log1.find("task '" + scenes[1].name + "' requeued") != std::string::npos);
  // The crashed node's task ran its third attempt on the other node, which took its WORK lock over
  // from the dead host once the lock was older than NF_WORK_LOCK_STALE_S.
  CHECK(down_seen);
  CHECK(resumed_after_crash);
  const auto hosts0 = hosts_of(scenes[0].name);
  REQUIRE(hosts0.size() == 3);
  CHECK(hosts0[1] == crashed_node);
  CHECK(hosts0[2] != crashed_node);
  CHECK(log0.find("was held by " + crashed_node) != std::string::npos);
  CHECK(log0.find("host '" + crashed_node + "' has not refreshed it") != std::string::npos);
  // Both nodes ran tasks.
  std::set<std::string> hosts_used;
  for (const Scene& s : scenes)
    for (const std::string& h : hosts_of(s.name)) hosts_used.insert(h);
  CHECK(hosts_used == std::set<std::string>{"nfnode1", "nfnode2"});
  // Each attempt was given its node's one GPU (a stand-in device; Vulkan's lavapipe runs it).
  for (const Scene& s : scenes) CHECK(occurrences(s.name, ", GPU 0)") == hosts_of(s.name).size());
  CHECK(shell(env + " squeue -h").empty());

  // Every task wrote what reconstruct writes; with 4 scenes (label long) the first is also compared
  // with the same scene run by reconstruct (the local test does that by default).
  for (const Scene& s : scenes)
    for (const std::string& stage : stage_names()) {
      INFO(s.name, " ", stage);
      CHECK(file_names(root / "work" / s.name / stage) == file_names(root / "work" / scenes[0].name / stage));
    }
  if (count >= 4) {
    reconstruct_reference(root / "scenes" / scenes[0].name, scenes[0].animal, root / "reference");
    check_like_reference(root / "work" / scenes[0].name, root / "reference");
  }
  fs::remove_all(root);
}
