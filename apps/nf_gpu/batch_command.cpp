#include "apps/nf_gpu/batch_command.hpp"

#include <cstdio>
#include <iostream>
#include <set>

#include "engine/batch/batch_report.hpp"
#include "engine/batch/local_backend.hpp"
#include "engine/batch/slurm_backend.hpp"
#include "engine/batch/task_run.hpp"
#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/text.hpp"

namespace nf_cli {

namespace fs = std::filesystem;

namespace {
const std::set<std::string> kSlurmOnly{"--partition", "--account", "--time", "--mem", "--gpus-per-task", "--cpus-per-task",
                                       "--max-parallel", "--signal-seconds", "--sbatch", "--dry-run"};
}  // namespace

struct BatchCommand::Values {
  std::string manifest, out, backend = "local", name, folder;
  nf::batch::LocalOptions local;
  nf::batch::SlurmOptions slurm;
  bool dry_run = false, rerun_done = false, as_json = false;
  int max_requeues = 3;
  std::string markdown, html;
};

BatchCommand::BatchCommand(CLI::App& app) : v_(std::make_shared<Values>()) {
  Values& v = *v_;
  command_ = app.add_subcommand("batch", "many scenes from a manifest, each a reconstruct task: on this machine or a Slurm cluster");
  command_->require_subcommand(1);
  command_->footer("manifest: JSON [{\"scene\": DIR, \"work\": DIR, \"settings\": {\"stage.key\": value}}] or CSV scene,work,stage.key,...\n"
                   "README, Many animals");

  run_ = command_->add_subcommand("run", "check the manifest, then run its scenes (local) or submit a job array (slurm)");
  run_->add_option("manifest", v.manifest, "the manifest (.json or .csv)")->required();
  run_->add_option("--out", v.out, "the batch folder: states, logs, reports (default: MANIFEST's name + .batch beside it)");
  run_->add_option("--backend", v.backend, "local or slurm")->check(CLI::IsMember({"local", "slurm"}));
  run_->add_option("--jobs", v.local.jobs, "local: tasks at once (default: one per GPU, or 1)")->check(CLI::Range(1, 256));
  run_->add_flag("--rerun-done", v.rerun_done, "run scenes already done again (their unchanged stages are skipped)");
  run_->add_option("--max-requeues", v.max_requeues, "slurm: times a stopped task requeues itself before it is left failed")
      ->check(CLI::Range(0, 100));
  run_->add_option("--partition", v.slurm.partition, "slurm: the partition");
  run_->add_option("--account", v.slurm.account, "slurm: the account");
  run_->add_option("--time", v.slurm.time, "slurm: the time limit of one task, e.g. 2:00:00");
  run_->add_option("--mem", v.slurm.mem, "slurm: memory per task, e.g. 32G");
  run_->add_option("--gpus-per-task", v.slurm.gpus_per_task, "slurm: GPUs per task (--gres=gpu:N)")->check(CLI::Range(0, 64));
  run_->add_option("--cpus-per-task", v.slurm.cpus_per_task, "slurm: CPU cores per task")->check(CLI::Range(0, 1024));
  run_->add_option("--max-parallel", v.slurm.max_parallel, "slurm: tasks running at once (the array's %N)")->check(CLI::Range(0, 100000));
  run_->add_option("--signal-seconds", v.slurm.signal_seconds, "slurm: SIGTERM this long before the time limit (default 120)")
      ->check(CLI::Range(10, 3600));
  run_->add_option("--sbatch", v.slurm.extra, "slurm: another #SBATCH option, e.g. --sbatch=--qos=low (repeatable)");
  run_->add_flag("--dry-run", v.dry_run, "slurm: print the job script; write and submit nothing");

  task_ = command_->add_subcommand("task", "run one task of a batch (what the local runner and the Slurm job script call)");
  task_->add_option("folder", v.folder, "the batch folder")->required();
  task_->add_option("--name", v.name, "the task's scene name")->required();
  task_->add_option("--max-requeues", v.max_requeues, "under Slurm: requeues allowed")->check(CLI::Range(0, 100));

  status_ = command_->add_subcommand("status", "one line per scene: state, stage reached, seconds per stage, scores, warnings");
  status_->add_option("folder", v.folder, "the batch folder")->required();
  status_->add_flag("--json", v.as_json, "machine-readable");

  report_ = command_->add_subcommand("report", "the status as Markdown and HTML pages with each scene's previews");
  report_->add_option("folder", v.folder, "the batch folder")->required();
  report_->add_option("--markdown", v.markdown, "the Markdown file (default: FOLDER/report.md)");
  report_->add_option("--html", v.html, "the HTML page (default: FOLDER/report.html)");
}

int BatchCommand::run() const {
  const Values& v = *v_;
  if (*run_) {
    const std::vector<nf::batch::BatchTask> tasks = nf::batch::read_manifest(v.manifest);
    const fs::path dir = v.out.empty() ? nf::batch::default_batch_folder(v.manifest) : fs::path(v.out);
    const nf::batch::BatchFolder folder(dir);
    if (v.backend == "local") {
      std::vector<std::string> slurm_only;
      for (const CLI::Option* o : run_->get_options())
        if (o->count() > 0 && kSlurmOnly.count(o->get_name()) > 0) slurm_only.push_back(o->get_name());
      if (!slurm_only.empty())
        throw nf::UsageError("batch run: " + nf::join(slurm_only) + " only apply to --backend slurm (this run is local)");
      folder.write(tasks, v.manifest, nf::batch::self_executable());
      nf::batch::LocalOptions o = v.local;
      o.devices = nf::batch::gpu_device_indices();
      if (o.devices.size() < 2) o.devices.clear();  // one GPU or none: every task takes the default device
      o.rerun_done = v.rerun_done;
      o.max_requeues = v.max_requeues;
      const nf::batch::LocalSummary s = nf::batch::run_local(folder, o);
      std::cout << nf::batch::rows_to_text(nf::batch::scene_rows(folder));
      std::printf("batch folder: %s (nf_gpu batch status|report %s)\n", dir.string().c_str(), dir.string().c_str());
      return s.exit_code;
    }
    if (run_->get_option("--jobs")->count() > 0) throw nf::UsageError("batch run: --jobs only applies to --backend local");
    nf::batch::SlurmOptions o = v.slurm;
    o.max_requeues = v.max_requeues;
    o.rerun_done = v.rerun_done;
    // The tasks not done yet, by the states a batch folder already holds (none: all of them).
    const std::vector<std::size_t> indices = nf::batch::tasks_to_submit(folder, tasks, v.rerun_done);
    const std::string script = nf::batch::sbatch_script(dir, tasks, nf::batch::self_executable(), indices, o);
    if (v.dry_run) {
      std::cout << (script.empty() ? "# every scene is done: nothing would be submitted\n" : script);
      return 0;
    }
    if (indices.empty()) {
      std::printf("batch: every scene is done or queued; nothing submitted (--rerun-done runs done ones again)\n");
      return 0;
    }
    folder.write(tasks, v.manifest, nf::batch::self_executable());
    const std::string job = nf::batch::submit(folder, script, tasks, indices);
    std::printf("batch: submitted job array %s (%zu task(s)); script %s\nfollow it with: nf_gpu batch status %s\n", job.c_str(),
                indices.size(), folder.sbatch_script().string().c_str(), dir.string().c_str());
    return 0;
  }
  if (*task_) {
    nf::batch::TaskRunOptions o;
    o.max_requeues = v.max_requeues;
    return nf::batch::run_task(nf::batch::BatchFolder(v.folder), v.name, o);
  }
  const nf::batch::BatchFolder folder(v.folder);
  const std::vector<nf::batch::SceneRow> rows = nf::batch::scene_rows(folder);
  if (*status_) {
    if (v.as_json) std::cout << nf::batch::rows_to_json(rows).dump(2) << "\n";
    else std::cout << nf::batch::rows_to_text(rows);
    return 0;
  }
  const fs::path markdown = v.markdown.empty() ? folder.dir() / "report.md" : fs::path(v.markdown);
  const fs::path html = v.html.empty() ? folder.dir() / "report.html" : fs::path(v.html);
  nf::write_file_atomic(markdown, nf::batch::rows_to_markdown(rows, fs::absolute(markdown).parent_path()));
  nf::write_file_atomic(html, nf::batch::rows_to_html(rows, fs::absolute(html).parent_path()));
  std::cout << nf::batch::rows_to_text(rows);
  std::printf("report: %s and %s\n", markdown.string().c_str(), html.string().c_str());
  return 0;
}

}  // namespace nf_cli
