// engine/batch without running a scene: manifests (JSON and CSV, defaults and overrides, the
// errors a user meets), the Slurm job script, how a task's exit is filed, the status rows read
// from WORK folders, the reports; and the WORK lock (taken, refused, stale locks taken over).
#include <doctest/doctest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <set>
#include <thread>

#include "engine/batch/batch_folder.hpp"
#include "engine/batch/batch_report.hpp"
#include "engine/batch/local_backend.hpp"
#include "engine/batch/manifest.hpp"
#include "engine/batch/slurm_backend.hpp"
#include "engine/batch/task_run.hpp"
#include "engine/core/error.hpp"
#include "engine/core/host.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/pipeline/work_lock.hpp"
#include "tests/support/files.hpp"

namespace fs = std::filesystem;
using nf::json;
using nf::test::slurp;
using nf::test::spit;

namespace {

fs::path fresh(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("nf_test_batch_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  nf::test::remove_at_exit(dir);
  return dir;
}

std::string error_of(const fs::path& manifest) {
  try {
    (void)nf::batch::read_manifest(manifest);
  } catch (const nf::InputError& e) {
    return e.what();
  }
  return "";
}

bool has(const std::vector<std::string>& v, const std::string& s) { return std::find(v.begin(), v.end(), s) != v.end(); }

// A pid that is surely not running: a child that has exited and been reaped.
pid_t dead_pid() {
  const pid_t pid = fork();
  if (pid == 0) _exit(0);
  int status = 0;
  waitpid(pid, &status, 0);
  return pid;
}

}  // namespace

TEST_CASE("a JSON manifest: defaults, per-scene overrides, names, WORK folders and the reconstruct arguments") {
  const fs::path dir = fresh("json");
  fs::create_directories(dir / "cats" / "tom");
  fs::create_directories(dir / "dogs" / "rex");
  spit(dir / "cats" / "tom" / "transforms.json", "{}");
  spit(dir / "m.json", R"({"defaults": {"quality": "draft", "settings": {"fur.steps": 120, "knowledge": {"preset": "cat"}}},
    "scenes": [{"scene": "cats/tom/transforms.json", "work": "out/tom"},
               {"scene": "dogs/rex", "name": "rex2", "quality": "default", "scene_scale": 2.5,
                "settings": {"knowledge.preset": "dog", "fur.steps": 40}}]})");
  const auto tasks = nf::batch::read_manifest(dir / "m.json");
  REQUIRE(tasks.size() == 2);
  CHECK(tasks[0].name == "tom");  // a transforms.json is named by its folder
  CHECK(tasks[0].work == (dir / "out" / "tom").lexically_normal());
  CHECK(tasks[0].quality == "draft");
  CHECK(has(tasks[0].settings, "fur.steps=120"));
  CHECK(has(tasks[0].settings, "knowledge.preset=cat"));
  CHECK(tasks[1].name == "rex2");
  CHECK(tasks[1].work == (dir / "work" / "rex2").lexically_normal());  // no "work": beside the manifest
  CHECK(tasks[1].quality == "default");
  CHECK(tasks[1].scene_scale == 2.5);
  // The scene's own settings come after the defaults, so reconstruct's last --set wins.
  const auto& s = tasks[1].settings;
  CHECK(std::find(s.begin(), s.end(), "fur.steps=40") > std::find(s.begin(), s.end(), "fur.steps=120"));
  CHECK(tasks[1].origin == "scenes[1]");
  // batch.json keeps them exactly.
  const nf::batch::BatchFolder folder(dir / "m.batch");
  folder.write(tasks, dir / "m.json", "/usr/bin/true");
  const auto back = folder.tasks();
  REQUIRE(back.size() == 2);
  CHECK(back[1].settings == tasks[1].settings);
  CHECK(back[1].scene_scale == 2.5);
  CHECK(folder.nf_gpu() == "/usr/bin/true");
}

TEST_CASE("a CSV manifest: the columns scene, work, and any setting; empty cells keep the default") {
  const fs::path dir = fresh("csv");
  fs::create_directories(dir / "a");
  fs::create_directories(dir / "b, with comma");
  spit(dir / "m.csv", "scene,work,quality,fur.steps,knowledge.preset\n"
                      "# a comment line\n"
                      "a,wa,draft,50,cat\n"
                      "\"b, with comma\",wb,,,lion\n");
  const auto tasks = nf::batch::read_manifest(dir / "m.csv");
  REQUIRE(tasks.size() == 2);
  CHECK(tasks[0].quality == "draft");
  CHECK(has(tasks[0].settings, "fur.steps=50"));
  CHECK(tasks[1].name == "b, with comma");
  CHECK(tasks[1].quality == "default");
  CHECK(tasks[1].settings == std::vector<std::string>{"knowledge.preset=lion"});
  CHECK(tasks[1].work == (dir / "wb").lexically_normal());
}

TEST_CASE("manifest errors name the file, the entry and the field") {
  const fs::path dir = fresh("errors");
  fs::create_directories(dir / "a");
  fs::create_directories(dir / "x" / "a");
  const auto check = [&](const std::string& name, const std::string& text, const std::vector<std::string>& expected) {
    spit(dir / name, text);
    const std::string message = error_of(dir / name);
    INFO(name, ": ", message);
    CHECK(!message.empty());
    for (const std::string& e : expected) CHECK(message.find(e) != std::string::npos);
  };
  check("unknown.json", R"([{"scene": "a", "setings": {}}])", {"unknown.json", "[0]", "setings", "did you mean 'settings'"});
  check("missing.json", R"([{"work": "w"}])", {"missing.json", "scene"});
  check("noscene.json", R"([{"scene": "nowhere"}])", {"scene 'nowhere'", "no such file"});
  check("badkey.json", R"([{"scene": "a", "settings": {"fur.stepz": 3}}])", {"[0] (scene 'a')", "stepz"});
  check("badvalue.json", R"([{"scene": "a", "settings": {"fur.steps": -4}}])", {"scene 'a'", "fur", "steps"});
  check("flat.json", R"([{"scene": "a", "settings": {"steps": 4}}])", {"'steps' is not \"stage.key\""});
  check("samework.json", R"([{"scene": "a", "work": "w"}, {"scene": "x/a", "name": "a2", "work": "w"}])",
        {"share the WORK folder", "a2"});
  check("samename.json", R"([{"scene": "a"}, {"scene": "x/a"}])", {"two scenes are named 'a'", "\"name\""});
  check("scale.json", R"([{"scene": "a", "scene_scale": 0}])", {"scene_scale must be a positive number"});
  check("empty.json", "[]", {"no scenes"});
  check("top.json", R"({"scenes": [{"scene": "a"}], "default": {}})", {"unknown field 'default'", "did you mean 'defaults'"});
  check("defaults.json", R"({"defaults": {"qualty": "draft"}, "scenes": [{"scene": "a"}]})", {"defaults", "qualty", "did you mean 'quality'"});
  check("noname.json", R"([{"scene": "a", "name": ""}])", {"[0]", "cannot be a file name"});
  check("badline.csv", "scene,work,name,knowledge.preset,fur.steps\na,w1,a1,cat,10\na,w2,a2,cat,-3\n", {"badline.csv: line 3", "steps"});
  check("unreadable.json", "", {"unreadable.json"});
  check("short.csv", "scene,work\na\n", {"short.csv: line 2", "1 fields where the header has 2"});
  check("column.csv", "scene,wrok\na,w\n", {"column 'wrok'", "did you mean 'work'"});
  check("quote.csv", "scene,work\n\"a,w\n", {"line 2", "quoted field is not closed"});
  // Bytes that are not UTF-8 in a setting (a fuzzer's find): an error quoting them, not a crash.
  check("bytes.csv", "scene,work,knowledge.preset,fur.steps\na,w,cat,4\xc5\xc5" "0\n", {"bytes.csv: line 2", "not UTF-8"});
  check("m.txt", "scene\na\n", {"neither .json nor .csv"});
}

TEST_CASE("the Slurm job script: an array of the tasks not done, requeueable, SIGTERM to nf_gpu before the limit") {
  const fs::path dir = fresh("slurm");
  for (const char* s : {"a", "b", "c", "d"}) fs::create_directories(dir / s);
  spit(dir / "m.json", R"({"defaults": {"settings": {"knowledge.preset": "cat"}}, "scenes": [{"scene": "a"}, {"scene": "b"}, {"scene": "c"}, {"scene": "d"}]})");
  const nf::batch::BatchFolder folder(dir / "m.batch");
  folder.write(nf::batch::read_manifest(dir / "m.json"), dir / "m.json", "/opt/nf gpu/nf_gpu");
  nf::batch::TaskState done;
  done.state = "done";
  folder.write_state("c", done);
  const auto tasks = folder.tasks();
  const auto indices = nf::batch::tasks_to_submit(folder, tasks, false);
  CHECK(indices == std::vector<std::size_t>{0, 1, 3});
  CHECK(nf::batch::tasks_to_submit(folder, tasks, true).size() == 4);
  nf::batch::SlurmOptions o;
  o.partition = "gpu";
  o.time = "2:00:00";
  o.gpus_per_task = 1;
  o.max_parallel = 2;
  o.extra = {"--qos=low"};
  const std::string script = nf::batch::sbatch_script(folder.dir(), tasks, "/opt/nf gpu/nf_gpu", indices, o);
  INFO(script);
  for (const char* line : {"#SBATCH --array=0-1,3%2\n", "#SBATCH --requeue\n", "#SBATCH --signal=B:TERM@120\n", "#SBATCH --partition=gpu\n",
                           "#SBATCH --time=2:00:00\n", "#SBATCH --gres=gpu:1\n", "#SBATCH --qos=low\n", "#SBATCH --open-mode=append\n",
                           "names=(a b c d)\n", "#SBATCH --job-name=nf_gpu-m.batch\n"})
    CHECK(script.find(line) != std::string::npos);
  // exec: the batch shell becomes nf_gpu, so the B: signal reaches the stages; the path is quoted.
  CHECK(script.find("exec '/opt/nf gpu/nf_gpu' batch task " + fs::absolute(folder.dir()).string() +
                    " --name=\"${names[$SLURM_ARRAY_TASK_ID]}\" --max-requeues 3\n") != std::string::npos);
  CHECK(nf::batch::sbatch_script(folder.dir(), tasks, "/x", {}, o).empty());
  // #SBATCH cannot quote a path: a batch folder with a blank is refused, naming it.
  CHECK_THROWS_WITH_AS(nf::batch::sbatch_script(dir / "my batch", tasks, "/x", indices, o), doctest::Contains("my batch"), nf::InputError);
}

TEST_CASE("the local runner: a GPU per slot (NF_DEVICE), the cores shared on a CPU driver, done tasks skipped, a killed task filed") {
  const fs::path dir = fresh("local");
  for (const char* s : {"a", "b", "c", "d"}) fs::create_directories(dir / s);
  spit(dir / "m.json", R"({"defaults": {"settings": {"knowledge.preset": "cat"}}, "scenes": [{"scene": "a"}, {"scene": "b"}, {"scene": "c"}, {"scene": "d"}]})");
  // A stand-in for nf_gpu: `batch task DIR --name N ...` records its environment and files itself
  // done, except the scene "d", which dies by SIGKILL before it can file anything.
  const fs::path fake = dir / "fake_nf_gpu.sh";
  spit(fake, "#!/bin/sh\n"
             "name=${4#--name=}\n"
             "echo \"NF_DEVICE=${NF_DEVICE:-none} LP_NUM_THREADS=${LP_NUM_THREADS:-none}\" > \"$3/env-$name\"\n"
             "sleep 0.3\n"
             "[ \"$name\" = d ] && kill -9 $$\n"
             "printf '{\"state\": \"done\", \"attempts\": 1}' > \"$3/tasks/$name.json\"\n");
  fs::permissions(fake, fs::perms::owner_all);
  const nf::batch::BatchFolder folder(dir / "m.batch");
  folder.write(nf::batch::read_manifest(dir / "m.json"), dir / "m.json", fake);
  nf::batch::TaskState done;
  done.state = "done";
  folder.write_state("c", done);

  nf::batch::LocalOptions gpus;
  gpus.devices = {"3", "5"};
  const auto summary = nf::batch::run_local(folder, gpus);
  CHECK(summary.done == 2);
  CHECK(summary.stopped == 1);
  CHECK(summary.skipped == 1);
  CHECK(summary.exit_code == 1);
  CHECK_FALSE(fs::exists(folder.dir() / "env-c"));  // done already
  // Two slots, one GPU each: a and b started together on devices 3 and 5, d took a freed slot.
  std::set<std::string> seen;
  for (const char* s : {"a", "b", "d"}) seen.insert(slurp(folder.dir() / (std::string("env-") + s)));
  CHECK(seen.count("NF_DEVICE=3 LP_NUM_THREADS=none\n") == 1);
  CHECK(seen.count("NF_DEVICE=5 LP_NUM_THREADS=none\n") == 1);
  const nf::batch::TaskState killed = folder.state("d");
  CHECK(killed.state == "stopped");
  CHECK(killed.exit_code == 128 + 9);
  CHECK(killed.message.find("killed by signal 9") != std::string::npos);

  // No GPU: N slots share the cores.
  nf::batch::LocalOptions cpu;
  cpu.jobs = 2;
  cpu.cores = 8;
  cpu.rerun_done = true;
  (void)nf::batch::run_local(folder, cpu);
  CHECK(slurp(folder.dir() / "env-a") == "NF_DEVICE=none LP_NUM_THREADS=4\n");
  CHECK(slurp(folder.dir() / "env-c") == "NF_DEVICE=none LP_NUM_THREADS=4\n");

  // A task another runner of this host is running is left to it.
  nf::batch::TaskState live;
  live.state = "running";
  live.host = nf::host_name();
  live.pid = getpid();
  folder.write_state("a", live);
  fs::remove(folder.dir() / "env-a");
  const auto again = nf::batch::run_local(folder, cpu);
  CHECK_FALSE(fs::exists(folder.dir() / "env-a"));
  CHECK(again.skipped == 1);
}

TEST_CASE("a task's exit is filed as done, failed (a rerun cannot fix it) or stopped (a rerun resumes)") {
  CHECK(nf::batch::may_requeue(0, 3));
  CHECK(nf::batch::may_requeue(2, 3));
  CHECK_FALSE(nf::batch::may_requeue(3, 3));
  CHECK_FALSE(nf::batch::may_requeue(0, 0));
  CHECK(nf::batch::verdict_of(nf::batch::kBusyExitCode, "").retryable);
  CHECK(nf::batch::verdict_of(0, "").state == "done");
  for (int code : {1, 2}) {
    const auto v = nf::batch::verdict_of(code, "bad");
    CHECK(v.state == "failed");
    CHECK_FALSE(v.retryable);
  }
  for (int code : {3, 130, 143, 137}) {
    const auto v = nf::batch::verdict_of(code, "");
    CHECK(v.state == "stopped");
    CHECK(v.retryable);
  }
}

TEST_CASE("under Slurm a task takes the Vulkan device of the first GPU Slurm gave it, where several are visible") {
  using nf::batch::nf_device_for_slurm_gpus;
  const std::vector<std::string> four{"0", "1", "2", "3"};  // four discrete GPUs, in the driver's order
  CHECK(nf_device_for_slurm_gpus("0", four) == "0");
  CHECK(nf_device_for_slurm_gpus("2", four) == "2");
  CHECK(nf_device_for_slurm_gpus("3,1", four) == "3");  // a task given two GPUs runs on the first
  // Vulkan's indices are of all devices; a machine's discrete GPUs need not be 0..N-1 among them.
  CHECK(nf_device_for_slurm_gpus("1", {"1", "2"}) == "2");
  // The default device where nothing else is sure: device cgroups leave one GPU visible, the number
  // is beyond the devices seen, no GPU was given, or the variable is not a list of numbers.
  CHECK(nf_device_for_slurm_gpus("3", {"0"}).empty());
  CHECK(nf_device_for_slurm_gpus("4", four).empty());
  CHECK(nf_device_for_slurm_gpus("", four).empty());
  CHECK(nf_device_for_slurm_gpus("(null)", four).empty());
  CHECK(nf_device_for_slurm_gpus("1", {}).empty());  // no GPU at all (a CPU driver)
}

TEST_CASE("a task whose WORK another live run holds leaves that run's state alone and exits 75") {
  const fs::path dir = fresh("busy");
  fs::create_directories(dir / "a");
  spit(dir / "m.json", R"({"defaults": {"settings": {"knowledge.preset": "cat"}}, "scenes": [{"scene": "a", "work": "wa"}]})");
  const nf::batch::BatchFolder folder(dir / "m.batch");
  folder.write(nf::batch::read_manifest(dir / "m.json"), dir / "m.json", "/usr/bin/true");
  nf::batch::TaskState theirs;
  theirs.state = "running";
  theirs.attempts = 1;
  theirs.host = "node7";
  theirs.job = "12_0";
  folder.write_state("a", theirs);
  const std::string before = slurp(folder.state_file("a"));
  {
    const nf::pipeline::WorkLock held(dir / "wa", "the other copy");
    nf::batch::TaskRunOptions o;
    o.log_to_file = false;
    CHECK(nf::batch::run_task(folder, "a", o) == nf::batch::kBusyExitCode);
  }
  std::signal(SIGTERM, SIG_DFL);  // the task ignores signals once it files
  std::signal(SIGINT, SIG_DFL);
  CHECK(slurp(folder.state_file("a")) == before);
}

TEST_CASE("status rows: the stage reached, seconds and scores from the WORK records, and a task whose process died") {
  const fs::path dir = fresh("rows");
  fs::create_directories(dir / "a");
  fs::create_directories(dir / "b");
  spit(dir / "m.json", R"({"defaults": {"settings": {"knowledge.preset": "cat"}}, "scenes": [{"scene": "a", "work": "wa"}, {"scene": "b", "work": "wb"}]})");
  const nf::batch::BatchFolder folder(dir / "m.batch");
  folder.write(nf::batch::read_manifest(dir / "m.json"), dir / "m.json", "/usr/bin/true");
  const auto record = [&](const std::string& work, const std::string& stage, double seconds, const json& summary) {
    fs::create_directories(dir / work / stage);
    spit(dir / work / stage / "stage.json", json{{"key", "k"}, {"seconds", seconds}, {"summary", summary}}.dump());
  };
  record("wa", "neus", 12.5, {{"held_out", {{"psnr_in_mask_mean", 23.25}}}});
  record("wa", "knowledge", 0.5, {{"warnings", {"the scale <differs> by 38 %"}}, {"scale", {{"cm_per_unit", 72.0}}}});
  record("wa", "fur", 80, {{"held_out", {{"orientation_error_deg", 31.5}, {"silhouette_iou", 0.75}}},
                           {"groom", {{"fscore", {{"2cm_20deg", 96.5}, {"2mm_20deg", 21.0}}}}}});
  nf::batch::TaskState a;
  a.state = "done";
  a.attempts = 2;
  folder.write_state("a", a);
  nf::batch::TaskState b;
  b.state = "running";
  b.host = nf::host_name();
  b.pid = dead_pid();
  folder.write_state("b", b);
  auto rows = nf::batch::scene_rows(folder);
  REQUIRE(rows.size() == 2);
  CHECK(rows[1].state == "lost");
  // A live task shows the stage it is in.
  b.pid = getpid();
  folder.write_state("b", b);
  fs::create_directories(dir / "wb" / "defur.partial");
  CHECK(nf::batch::scene_rows(folder)[1].stage_running == "defur");
  CHECK(nf::batch::rows_to_text(nf::batch::scene_rows(folder)).find("(defur running on " + nf::host_name() + ")") != std::string::npos);
  b.pid = dead_pid();
  folder.write_state("b", b);
  rows = nf::batch::scene_rows(folder);
  CHECK(rows[0].stage_reached == "fur");  // stage order, not file order
  REQUIRE(rows[0].stage_seconds.size() == 3);
  CHECK(rows[0].stage_seconds[0] == std::pair<std::string, double>{"neus", 12.5});
  CHECK(rows[0].scores["fur_F_2mm"] == 21.0);
  CHECK(rows[0].scores["neus_held_out_psnr"] == 23.25);
  CHECK(rows[0].warnings == std::vector<std::string>{"knowledge: the scale <differs> by 38 %"});
  CHECK(rows[1].state == "lost");
  CHECK(rows[1].stage_reached.empty());
  const std::string text = nf::batch::rows_to_text(rows);
  CHECK(text.find("F(2mm) 21.0") != std::string::npos);
  CHECK(text.find("2 scene(s): 1 done 1 lost") != std::string::npos);
  const json j = nf::batch::rows_to_json(rows);
  CHECK(j[0]["seconds"]["fur"] == 80);
  // The page escapes what scenes and stages wrote.
  const std::string html = nf::batch::rows_to_html(rows, folder.dir());
  CHECK(html.find("&lt;differs&gt;") != std::string::npos);
  CHECK(html.find("<differs>") == std::string::npos);
  const std::string md = nf::batch::rows_to_markdown(rows, folder.dir());
  CHECK(md.find("| a | done | 2 | fur |") != std::string::npos);
}

TEST_CASE("the WORK lock: one run at a time, a dead holder's lock taken over, a live one refused") {
  const fs::path work = fresh("lock") / "work";
  const fs::path file = nf::pipeline::WorkLock::file(work);
  {
    const nf::pipeline::WorkLock lock(work, "first");
    const json holder = nf::pipeline::WorkLock::holder(work);
    CHECK(holder["pid"] == long(getpid()));
    CHECK(holder["host"] == nf::host_name());
    std::string message;
    try {
      const nf::pipeline::WorkLock second(work, "second");
    } catch (const nf::InputError& e) {
      message = e.what();
    }
    INFO(message);
    CHECK(message.find("in use by another nf_gpu run") != std::string::npos);
    CHECK_THROWS_AS(nf::pipeline::WorkLock(work, "third"), nf::pipeline::WorkBusyError);
    CHECK(message.find("pid " + std::to_string(getpid())) != std::string::npos);
    CHECK(message.find("first") != std::string::npos);
    CHECK(fs::exists(file));  // the refused run left the holder's lock alone
  }
  CHECK_FALSE(fs::exists(file));  // released

  SUBCASE("a lock of a process of this host that has ended is taken over") {
    spit(file, json{{"host", nf::host_name()}, {"pid", long(dead_pid())}, {"started", "x"}, {"command", "old"}}.dump());
    const nf::pipeline::WorkLock lock(work, "new");
    CHECK(nf::pipeline::WorkLock::holder(work)["command"] == "new");
  }
  SUBCASE("another host's lock: refused while refreshed, taken over once it is older than NF_WORK_LOCK_STALE_S") {
    spit(file, json{{"host", "some-other-node"}, {"pid", 1}, {"started", "x"}, {"command", "remote"}}.dump());
    CHECK_THROWS_AS(nf::pipeline::WorkLock(work, "new"), nf::InputError);
    fs::last_write_time(file, fs::file_time_type::clock::now() - std::chrono::seconds(100));
    setenv("NF_WORK_LOCK_STALE_S", "60", 1);
    {
      const nf::pipeline::WorkLock lock(work, "new");
      CHECK(nf::pipeline::WorkLock::holder(work)["command"] == "new");
    }
    unsetenv("NF_WORK_LOCK_STALE_S");
  }
  SUBCASE("the holder refreshes its lock, and stops its run when another took it over") {
    setenv("NF_WORK_LOCK_STALE_S", "2", 1);  // a refresh every 0.2 s
    {
      const nf::pipeline::WorkLock lock(work, "mine");
      fs::last_write_time(file, fs::file_time_type::clock::now() - std::chrono::seconds(100));
      std::this_thread::sleep_for(std::chrono::milliseconds(700));
      CHECK(fs::file_time_type::clock::now() - fs::last_write_time(file) < std::chrono::seconds(2));
      CHECK_FALSE(nf::interrupted());
      spit(file, json{{"host", "elsewhere"}, {"pid", 7}, {"started", "x"}, {"command", "theirs"}}.dump());
      std::this_thread::sleep_for(std::chrono::milliseconds(700));
      CHECK(nf::interrupted());  // the stages stop as on Ctrl-C, saving their checkpoints
    }
    nf::set_interrupted(false);
    unsetenv("NF_WORK_LOCK_STALE_S");
    CHECK(nf::pipeline::WorkLock::holder(work)["command"] == "theirs");
  }
  SUBCASE("a file that is not a lock is never removed") {
    spit(file, "somebody's notes");
    std::string message;
    try {
      const nf::pipeline::WorkLock lock(work, "new");
    } catch (const nf::InputError& e) {
      message = e.what();
    }
    CHECK(message.find("not a lock nf_gpu wrote") != std::string::npos);
    CHECK(slurp(file) == "somebody's notes");
  }
  SUBCASE("a lock replaced by another taker is not removed by the first holder") {
    {
      const nf::pipeline::WorkLock lock(work, "mine");
      spit(file, json{{"host", "elsewhere"}, {"pid", 7}, {"started", "x"}, {"command", "theirs"}}.dump());
    }
    CHECK(nf::pipeline::WorkLock::holder(work)["command"] == "theirs");
  }
}
