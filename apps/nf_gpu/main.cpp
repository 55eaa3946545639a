// nf_gpu: the command line. Parsing and printing only; the work lives in engine/.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>

#include "apps/nf_gpu/batch_command.hpp"
#include "engine/bench/suites.hpp"
#include "engine/body/quadruped.hpp"
#include "engine/core/error.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/core/text.hpp"
#include "engine/core/json.hpp"
#include "engine/core/log.hpp"
#include "engine/fur/prior_evaluation.hpp"
#include "engine/fur/prior_training.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gradcheck/catalog.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/metrics/metrics_report.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/pipeline/export_stage.hpp"
#include "engine/pipeline/groom_edit.hpp"
#include "engine/pipeline/groom_pose.hpp"
#include "engine/pipeline/knowledge_stage.hpp"
#include "engine/prepare/prepare_scene.hpp"
#include "engine/synth/preview.hpp"
#include "engine/orient/scene_orientation.hpp"
#include "engine/pipeline/stages.hpp"
#include "engine/synth/strand_renderer.hpp"
#include "engine/synth/synth_scene.hpp"
#include "engine/synth/world_frame.hpp"

namespace {

using nf::json;

void print_profile(const nf::gpu::Context& context) {
  const auto totals = context.pass_totals();
  if (totals.empty()) return;
  std::cerr << "GPU time per pass:\n";
  for (const auto& [name, t] : totals)
    std::fprintf(stderr, "  %-32s %10.3f ms  (%llu runs, %.3f ms each)\n", name.c_str(), t.milliseconds,
                 (unsigned long long)t.count, t.count ? t.milliseconds / double(t.count) : 0.0);
}

int run_info(bool as_json) {
  const auto devices = nf::gpu::Context::enumerate_devices();
  nf::gpu::Context context;
  if (as_json) {
    json out{{"chosen", nf::gpu::to_json(context.info())}, {"devices", json::array()}};
    for (const auto& d : devices) out["devices"].push_back({{"index", d.index}, {"name", d.name}, {"type", d.type}});
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  const auto& i = context.info();
  const auto& l = i.limits;
  const auto& f = i.features;
  std::cout << "device: " << i.name << " (" << i.type << ", " << i.driver << ", " << i.driver_info << ", Vulkan "
            << i.api_version << ")\n";
  std::cout << "memory: " << i.device_memory_bytes / (1024 * 1024) << " MiB device-local\n";
  std::cout << "limits: storage buffer range " << l.max_storage_buffer_range / (1024 * 1024) << " MiB, allocation "
            << l.max_allocation_size / (1024 * 1024) << " MiB, push constants " << l.max_push_constants_size
            << " B, shared memory " << l.max_compute_shared_memory / 1024 << " KiB, subgroup " << l.subgroup_size
            << ", workgroup <= " << l.max_workgroup_invocations << " invocations\n";
  std::cout << "features: float atomic add " << (f.float32_atomic_add_buffer ? "yes" : "no") << ", fp16 "
            << (f.float16 ? "yes" : "no") << ", int64 " << (f.int64 ? "yes" : "no") << ", timestamps "
            << (f.timestamps ? "yes" : "no") << ", push descriptors " << (f.push_descriptors ? "yes" : "no")
            << ", subgroup ops";
  for (const auto& op : f.subgroup_operations) std::cout << " " << op;
  std::cout << "\n";
  for (const auto& q : i.quirks) std::cout << "quirk: " << q << "\n";
  std::cout << "all devices (NF_DEVICE=<index|name> picks one):\n";
  for (const auto& d : devices)
    std::cout << "  " << d.index << ": " << d.name << " (" << d.type << ")" << (d.name == i.name ? "  <- chosen" : "")
              << "\n";
  return 0;
}

int run_gradcheck(const std::string& only, bool as_json) {
  nf::gpu::Context context;
  std::vector<nf::gradcheck::Row> rows;
  bool found = false;
  for (const auto& kernel : nf::gradcheck::all_kernels()) {
    if (!only.empty() && kernel->name() != only) continue;
    found = true;
    const auto r = nf::gradcheck::run_checks(context, *kernel);
    rows.insert(rows.end(), r.begin(), r.end());
  }
  if (!found) {
    std::string names;
    for (const auto& kernel : nf::gradcheck::all_kernels()) names += " " + kernel->name();
    throw nf::UsageError("no differentiable kernel named '" + only + "'; kernels:" + names);
  }
  if (as_json)
    std::cout << nf::gradcheck::to_json(rows).dump(2) << "\n";
  else
    nf::gradcheck::print_table(std::cout, rows);
  const bool ok = nf::gradcheck::all_passed(rows);
  std::cerr << (ok ? "gradcheck: all checks passed\n" : "gradcheck: FAILED\n");
  return ok ? 0 : int(nf::ExitCode::DeviceOrInternal);
}

int print_surface_metrics(const json& out) {
  const json& m = out["surface"];
  std::printf("%s against %s (%llu samples each, %g cm per unit from %s)\n", out["mesh"].get<std::string>().c_str(),
              out["reference"].get<std::string>().c_str(), (unsigned long long)m["samples"].get<std::uint64_t>(),
              out["cm_per_unit"].get<double>(), out["scale_source"].get<std::string>().c_str());
  std::printf("  chamfer mm          mean %.4g  min %.4g  max %.4g\n", m["chamfer_mm"]["mean"].get<double>(),
              m["chamfer_mm"]["min"].get<double>(), m["chamfer_mm"]["max"].get<double>());
  std::printf("  accuracy mm         %.4g\n  completeness mm     %.4g\n", m["accuracy_mm"].get<double>(),
              m["completeness_mm"].get<double>());
  std::printf("  normal consistency  %.4f\n", m["normal_consistency"].get<double>());
  const json& f = m["fscore"];
  std::printf("  F-score at %g mm    precision %.2f  recall %.2f  F %.2f\n", f["threshold_mm"].get<double>(),
              f["precision"].get<double>(), f["recall"].get<double>(), f["fscore"].get<double>());
  return 0;
}

int print_strand_metrics(const json& out) {
  std::cout << "strands: " << out["strands"] << " sampled from " << out["pred"].get<std::string>() << " ("
            << out["points_per_strand"] << " points each, " << out["cm_per_unit"].get<double>() << " cm per unit from "
            << out["scale_source"].get<std::string>() << ")\n";
  for (const auto& [key, value] : out["consistency"].items()) std::printf("  %-28s %12.6g\n", key.c_str(), value.get<double>());
  if (out.contains("match")) {
    std::cout << "against " << out["gt"].get<std::string>() << ":\n  distance  angle  directed  precision  recall  F-score\n";
    for (const auto& m : out["match"])
      std::printf("  %5.2g cm %5.0f°  %-8s  %9.2f  %6.2f  %7.2f\n", m["distance_cm"].get<double>(),
                  m["angle_deg"].get<double>(), m["directed"].get<bool>() ? "yes" : "no", m["precision"].get<double>(),
                  m["recall"].get<double>(), m["fscore"].get<double>());
  }
  if (out.contains("tips_to_outer"))
    std::printf("strand tips against the outer surface: two-way chamfer %.4g mm\n",
                out["tips_to_outer"]["two_way_mm"].get<double>());
  return 0;
}

int run_metrics(const nf::metrics::MetricsRequest& r, bool as_json) {
  json out;
  if (!r.mesh.empty() || !r.reference.empty()) {
    if (r.mesh.empty() || r.reference.empty()) throw nf::UsageError("surface metrics need both --mesh and --ref");
    out = nf::metrics::surface_report(r);
  } else {
    if (r.pred.empty()) throw nf::UsageError("metrics need --pred (strands) or --mesh and --ref (surfaces)");
    out = nf::metrics::strand_report(r);
  }
  if (as_json) {
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  return out.contains("surface") ? print_surface_metrics(out) : print_strand_metrics(out);
}

int run_synth(const std::string& out, const nf::synth::SynthOptions& options) {
  const json info = nf::synth::synthesize_scene(out, options);
  std::printf("synth: %s, %u views at %ux%u, %u strands -> %s (%.1f s: body %.1f, fur %.1f, envelope %.1f, render %.1f)\n",
              options.animal.c_str(), options.views, options.resolution, options.resolution, options.strands, out.c_str(),
              info["timings"]["total_s"].get<double>(), info["timings"]["body_s"].get<double>(),
              info["timings"]["fur_s"].get<double>(), info["timings"]["envelope_s"].get<double>(),
              info["timings"]["render_s"].get<double>());
  return 0;
}

int run_prepare(const nf::prepare::PrepareOptions& options) {
  const json report = nf::prepare::prepare_scene(options);
  std::printf("prepare: %zu of %zu photos placed, reprojection error %.2f px, %zu points -> %s (%.1f s)\n",
              report["placed"].get<std::size_t>(), report["photos"].get<std::size_t>(), report["reprojection_error_px"].get<double>(),
              report["points"].get<std::size_t>(), options.out.string().c_str(), report["seconds"]["total"].get<double>());
  if (report["cm_per_unit"].is_number())
    std::printf("prepare: %.4g cm per scene unit (from %s)\n", report["cm_per_unit"].get<double>(), report["unit_from"].get<std::string>().c_str());
  return 0;
}

int run_orient(const nf::orient::SceneOrientationOptions& options) {
  nf::gpu::Context context;
  const nf::orient::SceneOrientations result = nf::orient::write_scene_orientations(context, options);
  const auto views = std::count_if(result.files.begin(), result.files.end(), [](const auto& f) { return f.extension() == ".exr"; });
  std::printf("orient: %zu views -> %s\n", std::size_t(views), options.out.string().c_str());
  if (!result.truth.empty()) {
    // Against the true orientation: the figures the fur stage's orientation loss lives on.
    std::printf("%-10s %9s %12s %10s %14s %12s\n", "camera", "pixels", "median err", "reliable", "err reliable", "weighted err");
    double pixels = 0, median = 0, share = 0, reliable = 0, weighted = 0;
    for (const auto& [camera, a] : result.truth) {
      std::printf("%-10s %9llu %11.1f° %9.1f%% %13.1f° %11.1f°\n", camera.c_str(), static_cast<unsigned long long>(a.pixels), a.median_error_deg,
                  100 * a.reliable_share, a.median_error_reliable_deg, a.weighted_error_deg);
      pixels += double(a.pixels), median += a.median_error_deg, share += a.reliable_share, reliable += a.median_error_reliable_deg,
          weighted += a.weighted_error_deg;
    }
    const double n = double(result.truth.size());
    std::printf("%-10s %9.0f %11.1f° %9.1f%% %13.1f° %11.1f°  (means over the views)\n", "all", pixels / n, median / n, 100 * share / n,
                reliable / n, weighted / n);
  }
  return 0;
}

int run_render(const nf::synth::PreviewOptions& options) {
  const auto r = nf::synth::render_previews(options);
  std::printf("render: %zu views -> %s (strand radius %.4g scene units, coloured by %s, %.1f s)\n", r.files.size(),
              options.out.string().c_str(), r.strand_radius, r.coloring.c_str(), r.seconds);
  return 0;
}

int run_bench(const nf::bench::Options& options, const std::string& json_path, bool profile) {
  if (!json_path.empty()) nf::bench::check_records_file(json_path);
  nf::gpu::Context context;
  const json records = nf::bench::run_suite(context, options);
  std::cout << records.dump(2) << "\n";
  if (!json_path.empty()) nf::bench::write_records(json_path, records);
  if (profile) print_profile(context);
  return 0;
}

// Runs the stages; on Ctrl-C or SIGTERM prints how to resume and returns nullopt (the caller exits
// with interrupted_exit_code().
std::optional<std::vector<nf::pipeline::StageOutcome>> run_stages(nf::gpu::Context& context,
                                                                  const nf::pipeline::ReconstructOptions& options,
                                                                  const std::string& command_line) {
  nf::install_interrupt_handler();
  try {
    return nf::pipeline::reconstruct(context, options);
  } catch (const nf::Interrupted& e) {
    std::cerr << "nf_gpu: " << e.what() << "\nresume with the same command: " << command_line << "\n";
    return std::nullopt;
  }
}

// Where the export files are and how to open them (what reconstruct, edit and pose print last):
// only the files this run wrote, as export.json lists them.
void print_export_guide(const std::filesystem::path& dir) {
  std::set<std::string> written;
  for (const json& f : nf::io::read_json_file(dir / "export.json").value("files", json::array())) written.insert(f.value("file", ""));
  std::printf("groom and body in %s (metres, +y up, the animal facing +z):\n", dir.string().c_str());
  if (written.count("fur.usda"))
    std::printf("  fur.usda   curves + body in one USD file: Houdini (File > Import > USD), Unreal (USD Stage), Omniverse\n");
  std::printf("  body.glb   rigged body: Blender (File > Import > glTF 2.0), Unreal (Import), Houdini (glTF ROP/SOP)\n");
  for (const char* f : {"fur.ply", "fur.obj"})
    if (written.count(f)) std::printf("  %s    the strands as polylines for any tool\n", f);
  if (written.count("fur.hair")) {
    std::printf("  fur.hair   Cem Yuksel's hair format; Blender hair curves through the add-on:\n");
    std::printf("             blender -b -P tools/blender/nf_gpu_import.py -- %s (or install tools/blender as an add-on)\n",
                dir.string().c_str());
  }
  if (std::filesystem::exists(dir / "turntable.png")) std::printf("  previews: %s/turntable.png\n", dir.string().c_str());
  if (std::filesystem::exists(dir / "index.html")) std::printf("  open in a browser: %s\n", (std::filesystem::absolute(dir) / "index.html").string().c_str());
}

int run_reconstruct(const nf::pipeline::ReconstructOptions& options, bool as_json, bool profile,
                    const std::string& command_line) {
  nf::gpu::Context context;
  const auto ran = run_stages(context, options, command_line);
  if (!ran) return nf::interrupted_exit_code();
  const auto& outcomes = *ran;
  if (profile) print_profile(context);
  if (as_json) {
    json out = json::array();
    for (const auto& o : outcomes) {
      out.push_back({{"stage", o.name}, {"ran", o.ran}, {"seconds", o.seconds}, {"summary", o.summary}});
      if (!o.kept.empty()) out.back()["kept"] = o.kept;
    }
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  for (const auto& o : outcomes)
    std::printf("%-10s %s%s\n", o.name.c_str(), o.ran ? "ran in " : o.kept.empty() ? "unchanged, skipped" : "kept: ",
                o.ran ? (std::to_string(o.seconds) + " s").c_str() : o.kept.c_str());
  std::printf("outputs in %s\n", options.work.string().c_str());
  if (std::any_of(outcomes.begin(), outcomes.end(), [](const auto& o) { return o.name == "export"; }))
    print_export_guide(nf::pipeline::export_outputs(options.work).dir);
  return 0;
}

// `nf_gpu annotate`: the stages up to knowledge, then the region table, the scale and the warnings.
int run_annotate(const nf::pipeline::ReconstructOptions& options, bool as_json, const std::string& command_line) {
  nf::gpu::Context context;
  const auto ran = run_stages(context, options, command_line);
  if (!ran) return nf::interrupted_exit_code();
  const auto& outcomes = *ran;
  const nf::pipeline::KnowledgeOutputs out = nf::pipeline::knowledge_outputs(options.work);
  const nf::knowledge::Knowledge k = nf::knowledge::read_knowledge(out.knowledge());
  const json summary = outcomes.back().summary;
  if (as_json) {
    std::cout << json{{"knowledge", nf::knowledge::knowledge_to_json(k)}, {"summary", summary}}.dump(2) << "\n";
    return 0;
  }
  std::cout << nf::knowledge::region_table(k);
  const json scale = summary.value("scale", json::object());
  std::printf("scale: %.6g cm per scene unit (from %s)\n", scale.value("cm_per_unit", 0.0), scale.value("source", std::string("?")).c_str());
  for (const json& w : summary.value("warnings", json::array())) std::printf("warning: %s\n", w.get<std::string>().c_str());
  std::printf("%s (edit it and feed it back with --set knowledge.file=%s)\n", out.knowledge().string().c_str(),
              out.knowledge().string().c_str());
  return 0;
}

// `nf_gpu train-prior`: trains the strand prior, measures it and writes it with its record.
int run_train_prior(const std::string& out, nf::fur::PriorTrainingOptions options, std::uint32_t eval_strands,
                    std::uint32_t fit_iterations, bool as_json, const std::string& command_line) {
  const std::filesystem::path path(out);
  if (std::filesystem::exists(path)) {
    // Replace only an earlier strand prior, never somebody else's file.
    nf::gpu::Context probe;
    try {
      (void)nf::fur::StrandPrior::load(probe, path);
    } catch (const nf::InputError&) {
      throw nf::UsageError("--out " + out + " exists and is not a strand prior; choose another file");
    }
  }
  nf::gpu::Context context;
  nf::install_interrupt_handler();
  std::fprintf(stderr, "train-prior: %u steps of %u strands on %s\n", options.steps, options.batch, context.info().name.c_str());
  nf::fur::PriorTraining trained = nf::fur::train_strand_prior(context, options, [&](std::uint32_t step, double loss) {
    if (step % 500 == 1 || step == options.steps) std::fprintf(stderr, "train-prior: step %u loss %.3g\n", step, loss);
  });
  const json evaluation = nf::fur::evaluate_prior(*trained.prior, eval_strands, fit_iterations, options.seed);
  trained.prior->record = {{"command", command_line},
                           {"seed", options.seed},
                           {"steps", options.steps},
                           {"batch", options.batch},
                           {"lr", options.lr},
                           {"latent_noise", options.latent_noise},
                           {"latent_l2", options.latent_l2},
                           {"segment_weight", options.segment_weight},
                           {"device", context.info().name},
                           {"seconds", trained.seconds},
                           {"skipped_steps", trained.skipped_steps},
                           {"curve", trained.curve},
                           {"evaluation", evaluation},
                           {"data", "procedural strands (engine/fur/strand_shapes.cpp); no external data or weights"}};
  trained.prior->save(path);
  if (as_json) {
    std::cout << trained.prior->record.dump(2) << "\n";
    return 0;
  }
  std::printf("train-prior: %.0f s, final loss %.4g -> %s\n", trained.seconds, trained.curve.back()[2].get<double>(), out.c_str());
  std::printf("%-16s %24s %24s\n", "strands", "encode+decode mean / p95", "fitted mean / p95");
  for (const auto& [name, set] : evaluation["sets"].items())
    std::printf("%-16s %11.2f %% / %6.2f %% %11.2f %% / %6.2f %%\n", name.c_str(), 100 * set["encode_decode"]["mean"].get<double>(),
                100 * set["encode_decode"]["p95"].get<double>(), 100 * set["fitted"]["mean"].get<double>(),
                100 * set["fitted"]["p95"].get<double>());
  std::printf("(point error as a share of the strand's length)\n");
  return 0;
}

int run_edit(const nf::pipeline::EditOptions& options, bool as_json) {
  nf::gpu::Context context;
  nf::install_interrupt_handler();  // a stop removes this run's partial files (groom_edit.cpp)
  const json record = nf::pipeline::run_edit(context, options);
  if (as_json) {
    std::cout << record.dump(2) << "\n";
    return 0;
  }
  std::printf("edit: %s strands (was %s), inferred in %.1f s, exported in %.1f s\n", record["strands"]["after"].dump().c_str(),
              record["strands"]["before"].dump().c_str(), record["seconds"]["inference"].get<double>(), record["seconds"]["export"].get<double>());
  print_export_guide(options.out);
  return 0;
}

int run_pose(const nf::pipeline::PoseOptions& options, bool as_json) {
  nf::install_interrupt_handler();
  const json record = nf::pipeline::run_pose(options);
  if (as_json) {
    std::cout << record.dump(2) << "\n";
    return 0;
  }
  std::printf("pose: %zu joints rotated, %s strands moved with the skin in %.1f s\n", record["joints"].size(),
              record["export"]["strands"].dump().c_str(), record["seconds"].get<double>());
  print_export_guide(options.out);
  return 0;
}

// The command as typed, quoted where needed, for "resume with" messages.
std::string quoted_command_line(int argc, char** argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) line += (i ? " " : "") + nf::shell_quote(argv[i]);
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"nf_gpu: furless body mesh and strand-based fur from multi-view photos, on Vulkan compute"};
  app.require_subcommand(1);
  nf::ignore_file_size_signal();
  app.fallthrough();  // global flags such as --profile may follow the subcommand
  bool profile = false;
  app.add_flag("--profile", profile, "print GPU time per pass at exit");

  bool info_json = false;
  auto* info = app.add_subcommand("info", "Vulkan devices, the chosen one, its limits and features");
  info->add_flag("--json", info_json, "machine-readable output");

  std::string kernel_name;
  bool gradcheck_json = false;
  auto* gradcheck = app.add_subcommand("gradcheck", "check every differentiable kernel against references and finite differences");
  gradcheck->add_option("--kernel", kernel_name, "only this kernel (e.g. splat/segment_gaussian)");
  gradcheck->add_flag("--json", gradcheck_json, "machine-readable output");

  nf::bench::Options bench_options;
  std::string bench_json;
  auto* bench = app.add_subcommand("bench", "measure speed (with error) and write JSON records");
  bench->add_option("--suite", bench_options.suite, "suite to run")->check(CLI::IsMember(nf::bench::suite_names()));
  bench->add_option("--json", bench_json, "also write the records to this file");
  bench->add_flag("--quick", bench_options.quick, "smaller sizes and fewer repeats (smoke run)");
  bench->add_option("--torch-peer", bench_options.torch_peer,
                    "tools/bench_torch_nn.py: time PyTorch on the CPU as a peer (suite nn)");

  nf::metrics::MetricsRequest metrics_request;
  std::string metrics_pred, metrics_gt, metrics_outer, metrics_mesh, metrics_reference;
  double metrics_scale = 0;
  bool metrics_json = false;
  auto* metrics = app.add_subcommand("metrics", "strand metrics (paper supplementary): consistency, and P/R/F against ground truth");
  metrics->add_option("--pred", metrics_pred, "predicted strands (.hair, .ply, .obj, .usda)")->check(CLI::ExistingFile);
  metrics->add_option("--outer", metrics_outer, "outer surface mesh: two-way chamfer with the strand tips")->check(CLI::ExistingFile);
  metrics->add_option("--mesh", metrics_mesh, "surface metrics: this mesh (.ply, .obj, .glb)...")->check(CLI::ExistingFile);
  metrics->add_option("--ref", metrics_reference, "...against this reference mesh")->check(CLI::ExistingFile);
  metrics->add_option("--fscore-mm", metrics_request.fscore_mm, "surface F-score distance in mm (default 5)")->check(CLI::PositiveNumber);
  metrics->add_option("--gt", metrics_gt, "ground-truth strands")->check(CLI::ExistingFile);
  metrics->add_option("--scale", metrics_scale,
                      "cm per scene unit (100 for metres); required unless a scale.json or a synth scene's "
                      "gt/scene.json beside the files declares it")->check(CLI::PositiveNumber);
  metrics->add_option("--thresholds", metrics_request.thresholds,
                      "strand match thresholds: cm (2cm:20,3cm:30,4cm:40, the paper's; default), mm "
                      "(2mm:20,3mm:30,4mm:40) or a list such as 2cm:20,5mm:10");
  metrics->add_option("--strands", metrics_request.strands, "strands sampled from each side (default 100000)");
  metrics->add_option("--points", metrics_request.points, "points per resampled strand (default 100)");
  metrics->add_option("--seed", metrics_request.seed, "sampling seed");
  metrics->add_flag("--json", metrics_json, "machine-readable output");

  nf::synth::SynthOptions synth_options;
  std::string synth_out;
  auto* synth = app.add_subcommand("synth", "a procedural furry quadruped with ground truth (images, masks, cameras, strands, meshes)");
  synth->add_option("--animal", synth_options.animal, nf::join(nf::body::known_animals()))
      ->check(CLI::IsMember(nf::body::known_animals()));
  synth->add_option("--views", synth_options.views, "number of views, on two camera rings (default 36)")->check(CLI::Range(1, 10000));
  synth->add_option("--res", synth_options.resolution, "image width and height in pixels (default 512)")->check(CLI::Range(8, 8192));
  synth->add_option("--seed", synth_options.seed, "varies proportions, pose, fur and placement (default 1)");
  synth->add_option("--proportion-spread", synth_options.proportion_spread,
                    "each body proportion scaled by a seeded factor within 1 +- this (default 0.06; up to 0.3 for bodies far from the family's)")
      ->check(CLI::Range(0.0, 0.3));
  synth->add_option("--fur-length-spread", synth_options.fur_length_spread,
                    "each region's fur length scaled by a seeded factor within 1 +- this (default 0: the preset's lengths)")
      ->check(CLI::Range(0.0, 0.9));
  synth->add_option("--strands", synth_options.strands, "ground-truth strands (default 100000)")->check(CLI::Range(1, 20000000));
  synth->add_option("--spp-axis", synth_options.samples_per_axis, "anti-aliasing: s x s samples per pixel (default 3)")->check(CLI::Range(1, 16));
  synth->add_option("--shading", synth_options.shading, "how strands reflect light: kajiya-kay (default), two-lobe (Marschner's two highlights), matte")
      ->check(CLI::IsMember(nf::synth::hair_shading_names()));
  synth->add_option("--hair-width", synth_options.hair_width, "strands' rendered width as a multiple of the style's (default 1)")->check(CLI::Range(0.01, 100.0));
  synth->add_option("--noise", synth_options.photo_noise, "Gaussian sensor noise on the photos, sigma in levels of 255 (default 0)")->check(CLI::Range(0.0, 255.0));
  synth->add_option("--backdrop", synth_options.backdrop,
                    "what surrounds the animal: plain (one flat colour, default) or textured (a patterned floor and wall, as photos taken anywhere but a studio have)")
      ->check(CLI::IsMember(nf::synth::backdrop_names()));
  synth->add_option("--photo-format", synth_options.photo_format,
                    "png (lossless, default) or jpeg (quality 92, with a camera's EXIF: maker, model, focal length)")
      ->check(CLI::IsMember({"png", "jpeg"}));
  synth->add_option("--path", synth_options.camera_path,
                    "rings (a rig: two even rings, default) or handheld (a person walking round: uneven steps, heights, distances, aim and roll)")
      ->check(CLI::IsMember({"rings", "handheld"}));
  synth->add_option("--blurred-views", synth_options.blurred_views, "this many views (spread evenly) shaken during the exposure (default 0)");
  synth->add_option("--out", synth_out, "output folder (must be new, or an earlier synth scene with --overwrite)")->required();
  synth->add_option("--frame", synth_options.frame,
                    "world frame of the files: y-up-m (default) or z-up-mm (z up, millimetres, metres from the origin); the photos are the same")
      ->check(CLI::IsMember(nf::synth::world_frame_names()));
  synth->add_flag("--overwrite", synth_options.overwrite, "replace an earlier synth scene in --out");
  synth->add_flag("--true-orientation", synth_options.true_orientation,
                  "also write gt/orientation/<camera>.exr: the true on-screen orientation of the strands (nf_gpu orient scores its maps against it)");

  nf::prepare::PrepareOptions prepare_options;
  std::string prepare_images, prepare_video, prepare_out, prepare_masks, prepare_colmap, prepare_known;
  double prepare_scale = 0;
  auto* prepare = app.add_subcommand("prepare", "your own photos or video to a scene: cameras by COLMAP, masks, the photos and masks undistorted (transforms.json, images/, masks/)");
  auto* prepare_from_images = prepare->add_option("--images", prepare_images, "a folder of photos of the animal (PNG or JPEG), 30-80 taken around it");
  auto* prepare_from_video = prepare->add_option("--video", prepare_video, "a video circling the animal (any format ffmpeg reads); --frames sharp frames are taken from it");
  prepare_from_images->excludes(prepare_from_video);
  prepare->add_option("--frames", prepare_options.video_frames, "with --video: how many frames to keep, the sharpest of each stretch (default 60)")
      ->check(CLI::Range(8, 400))
      ->needs(prepare_from_video);
  prepare->add_option("--out", prepare_out, "the scene folder to write (must be new)")->required();
  prepare->add_option("--masks", prepare_masks, "one mask per photo (white animal on black), named like the photo; without it, the photos' alpha channel")
      ->check(CLI::ExistingDirectory);
  prepare->add_option("--colmap", prepare_colmap, "a COLMAP sparse model of these photos made elsewhere (cameras/images/points3D .bin or .txt): used instead of running COLMAP")
      ->check(CLI::ExistingDirectory);
  prepare->add_option("--scene-scale", prepare_scale, "cm per scene unit, when known (COLMAP's unit is arbitrary; without it the knowledge stage estimates the scale)")
      ->check(CLI::PositiveNumber);
  prepare->add_option("--known-distance", prepare_known,
                      "a JSON file: two points picked in two or more photos each and their distance in cm, which sets the unit "
                      "({\"cm\": 30, \"points\": [{\"a.jpg\": [x, y], \"b.jpg\": [x, y]}, {...}]}, pixels as a viewer shows them)")
      ->check(CLI::ExistingFile);
  prepare->add_option("--max-features", prepare_options.max_features, "SIFT features per photo (default 4096; matching time grows with its square)")
      ->check(CLI::Range(256, 65536));

  nf::synth::PreviewOptions render_options;
  std::string render_strands, render_mesh, render_scene, render_out;
  auto* render = app.add_subcommand("render", "shaded previews of strands over the body, a colour per region (a PNG per view)");
  render->add_option("--strands", render_strands, "strands (.hair, .ply, .obj, .usda)")->required();
  render->add_option("--mesh", render_mesh, "body mesh (.ply, .obj, .glb, .gltf); its regions colour the strands")->required();
  render->add_option("--scene", render_scene, "scene folder or transforms.json (any supported camera format)")->required();
  render->add_option("--views", render_options.views, "'all' (default) or camera indices, e.g. 0,5,9");
  render->add_option("--out", render_out, "output folder: <camera name>.png per view (created if needed)")->required();
  render->add_option("--spp-axis", render_options.samples_per_axis, "anti-aliasing: s x s samples per pixel (default 3)")->check(CLI::Range(1, 16));
  render->add_option("--width-scale", render_options.width_scale, "strand width factor (default 1: about one pixel at the animal)")->check(CLI::PositiveNumber);

  nf::orient::SceneOrientationOptions orient_options;
  std::string orient_scene, orient_out;
  auto* orient = app.add_subcommand("orient", "Gabor orientation maps of a scene's photos (EXR: orientation, confidence; PNG preview)");
  orient->add_option("--scene", orient_scene, "scene folder or transforms.json (any format nf_gpu reads)")->required();
  orient->add_option("--out", orient_out, "output folder: <camera>.exr and <camera>.png per view")->required();
  orient->add_option("--views", orient_options.views, "'all' (default) or camera indices like 0,5,9");

  nf::pipeline::ReconstructOptions reconstruct_options;
  bool reconstruct_json = false;
  std::string reconstruct_scene, reconstruct_out;
  std::string help_stage;
  bool help_markdown = false;
  auto* reconstruct = app.add_subcommand("reconstruct", "the method stage by stage (cached and resumable)");
  reconstruct->footer("stages, in order: " + nf::join(nf::pipeline::stage_names()) +
                      "\nevery stage's settings: nf_gpu reconstruct --help-stage STAGE (docs/settings.md)");
  auto* scene_option = reconstruct->add_option("--scene", reconstruct_scene, "scene folder or transforms.json (any format nf_gpu reads)");
  auto* out_option = reconstruct->add_option("--out", reconstruct_out, "WORK folder: one sub-folder per stage (created if needed)");
  auto* reconstruct_quality = reconstruct->add_option("--quality", reconstruct_options.quality,
                          nf::join(nf::pipeline::quality_names()) + " (default: default; on a CPU driver only draft "
                          "finishes in minutes)")
      ->check(CLI::IsMember(nf::pipeline::quality_names()));
  reconstruct->add_option("--from", reconstruct_options.run.from, "rerun this stage and the stages that depend on it");
  reconstruct->add_option("--to", reconstruct_options.run.to, "run only this stage and the stages it depends on");
  reconstruct->add_option("--set", reconstruct_options.settings, "override a stage setting: stage.key=value (repeatable)");
  reconstruct->add_flag("--json", reconstruct_json, "machine-readable summary");
  reconstruct->add_option("--scene-scale", reconstruct_options.scene_scale, "the scene's unit in cm (overrides the scene file and the eyes)")
      ->check(CLI::PositiveNumber);
  reconstruct->add_option("--help-stage", help_stage, "print the settings of this stage and exit");
  reconstruct->add_flag("--markdown", help_markdown, "with --help-stage: a markdown table");

  nf::pipeline::ReconstructOptions annotate_options;
  std::string annotate_scene, annotate_out;
  bool annotate_json = false;
  auto* annotate = app.add_subcommand("annotate", "the knowledge stage (and what it needs): fur per region from a VLM, a preset or a file");
  annotate->add_option("--scene", annotate_scene, "scene folder or transforms.json")->required();
  annotate->add_option("--out", annotate_out, "WORK folder (shared with reconstruct)")->required();
  auto* annotate_quality = annotate->add_option("--quality", annotate_options.quality, "quality of the stages before it (default: default)")
      ->check(CLI::IsMember(nf::pipeline::quality_names()));
  annotate->add_option("--set", annotate_options.settings,
                       "stage.key=value, e.g. knowledge.preset=cat, or knowledge.vlm=URL knowledge.model=NAME (repeatable)");
  annotate->add_option("--scene-scale", annotate_options.scene_scale, "the scene's unit in cm (overrides the scene file and the eyes)")
      ->check(CLI::PositiveNumber);
  annotate->add_flag("--json", annotate_json, "machine-readable output");

  nf::fur::PriorTrainingOptions prior_options;
  std::string prior_out;
  std::uint32_t prior_eval_strands = 2000, prior_fit_iterations = 100;
  bool prior_json = false;
  std::vector<std::uint32_t> prior_hidden;
  auto* train_prior = app.add_subcommand("train-prior", "train the strand prior (decoder from a 64-d latent to a 100-point strand) on procedural fur");
  train_prior->add_option("--out", prior_out, "weights file to write (.nfwt; an existing file must be a strand prior)")->required();
  train_prior->add_option("--steps", prior_options.steps, "training steps (default 6000)")->check(CLI::Range(1, 10000000));
  train_prior->add_option("--seed", prior_options.seed, "seed of the initialisation, the strands and the noise (default 1)");
  train_prior->add_option("--batch", prior_options.batch, "strands per step (default 2048)")->check(CLI::Range(8, 65536));
  train_prior->add_option("--hidden", prior_hidden, "hidden widths of both networks (default 128,128)")->delimiter(',')->check(CLI::Range(1, 1024));
  train_prior->add_option("--eval-strands", prior_eval_strands, "strands per evaluation set (default 2000)")->check(CLI::Range(10, 1000000));
  train_prior->add_option("--fit-iterations", prior_fit_iterations, "latent-fitting iterations in the evaluation (default 100)")->check(CLI::Range(0, 100000));
  train_prior->add_flag("--json", prior_json, "print the record as JSON");

  nf::pipeline::EditOptions edit_options;
  std::string edit_work, edit_out;
  std::uint32_t edit_strands = 0;
  bool edit_json = false;
  auto* edit = app.add_subcommand("edit", "re-infer and re-export the groom with per-region changes, without retraining");
  edit->add_option("--work", edit_work, "WORK folder of a finished reconstruct")->required();
  edit->add_option("--out", edit_out, "output folder (not inside WORK; created if needed)")->required();
  edit->add_option("--set", edit_options.sets, "REGION.length_cm=X, REGION.hair_diameter_mm=X or REGION.density=X (repeatable)");
  edit->add_option("--shave", edit_options.shave, "a region to shave (repeatable)");
  edit->add_option("--strands", edit_strands, "re-sample this many roots over the fur first")->check(CLI::Range(1u, 40000000u));
  edit->add_option("--seed", edit_options.seed, "seed of new roots (default 1)");
  edit->add_option("--quality", edit_options.quality, "previews' preset (default draft)")->check(CLI::IsMember(nf::pipeline::quality_names()));
  edit->add_option("--formats", edit_options.formats, "groom files, comma-separated: usda, hair, ply, obj (default usda,hair)");
  edit->add_flag("--json", edit_json, "print the record as JSON");

  nf::pipeline::PoseOptions pose_options;
  std::string pose_work, pose_out, pose_groom;
  bool pose_json = false;
  auto* pose = app.add_subcommand("pose", "pose body and fur with the fitted skeleton (linear blend skinning; strands follow their root)");
  pose->add_option("--work", pose_work, "WORK folder of a finished reconstruct")->required();
  pose->add_option("--out", pose_out, "output folder (not inside WORK; created if needed)")->required();
  pose->add_option("--set", pose_options.sets, "joint.NAME=rx,ry,rz: a rotation vector in degrees, export frame (repeatable)");
  pose->add_option("--groom", pose_groom, "pose an edit's folder instead of WORK's groom");
  pose->add_option("--quality", pose_options.quality, "previews' preset (default draft)")->check(CLI::IsMember(nf::pipeline::quality_names()));
  pose->add_option("--formats", pose_options.formats, "groom files, comma-separated: usda, hair, ply, obj (default usda,hair)");
  pose->add_flag("--json", pose_json, "print the record as JSON");

  // `nf_gpu help [COMMAND]` and a bare `nf_gpu` print the help, as most tools do.
  const nf_cli::BatchCommand batch(app);

  auto* help = app.add_subcommand("help", "this help, or a command's: nf_gpu help COMMAND");
  std::string help_topic;
  help->add_option("command", help_topic, "a command");
  if (argc == 1) {
    std::cout << app.help();
    return int(nf::ExitCode::Usage);
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : int(nf::ExitCode::Usage);
  }

  try {
    if (*help) {
      if (help_topic.empty()) {
        std::cout << app.get_formatter()->make_help(&app, "nf_gpu", CLI::AppFormatMode::Normal);  // app.help() is the selected command's
        return 0;
      }
      for (CLI::App* sub : app.get_subcommands({}))
        if (sub->get_name() == help_topic) {
          std::cout << sub->help();
          return 0;
        }
      std::vector<std::string> names;
      for (CLI::App* sub : app.get_subcommands({})) names.push_back(sub->get_name());
      throw nf::UsageError("help: no command '" + help_topic + "'" + nf::did_you_mean(help_topic, names) + " (commands: " + nf::join(names) + ")");
    }
    if (*info) return run_info(info_json);
    if (*gradcheck) return run_gradcheck(kernel_name, gradcheck_json);
    if (*bench) return run_bench(bench_options, bench_json, profile);
    if (*metrics) {
      metrics_request.pred = metrics_pred, metrics_request.gt = metrics_gt, metrics_request.outer = metrics_outer;
      metrics_request.mesh = metrics_mesh, metrics_request.reference = metrics_reference;
      if (metrics_scale > 0) metrics_request.scale = metrics_scale;
      return run_metrics(metrics_request, metrics_json);
    }
    if (*synth) return run_synth(synth_out, synth_options);
    if (*prepare) {
      prepare_options.images = prepare_images, prepare_options.video = prepare_video, prepare_options.out = prepare_out;
      prepare_options.known_distance = prepare_known;
      prepare_options.masks = prepare_masks, prepare_options.colmap_model = prepare_colmap;
      if (prepare_scale > 0) prepare_options.cm_per_unit = prepare_scale;
      return run_prepare(prepare_options);
    }
    if (*reconstruct) {
      if (!help_stage.empty()) {
        std::cout << nf::pipeline::describe_stage_settings(help_stage, help_markdown);
        return 0;
      }
      if (scene_option->count() == 0 || out_option->count() == 0)
        throw nf::UsageError("reconstruct needs --scene and --out (nf_gpu reconstruct --help)");
      reconstruct_options.scene = reconstruct_scene, reconstruct_options.work = reconstruct_out;
      reconstruct_options.run.quality_named = reconstruct_quality->count() > 0;
      return run_reconstruct(reconstruct_options, reconstruct_json, profile, quoted_command_line(argc, argv));
    }
    if (*annotate) {
      annotate_options.scene = annotate_scene, annotate_options.work = annotate_out, annotate_options.run.to = "knowledge";
      annotate_options.run.quality_named = annotate_quality->count() > 0;
      return run_annotate(annotate_options, annotate_json, quoted_command_line(argc, argv));
    }
    if (*train_prior) {
      if (!prior_hidden.empty()) prior_options.shape.encoder_hidden = prior_options.shape.decoder_hidden = prior_hidden;
      return run_train_prior(prior_out, prior_options, prior_eval_strands, prior_fit_iterations, prior_json,
                             quoted_command_line(argc, argv));
    }
    if (*orient) {
      orient_options.scene = orient_scene, orient_options.out = orient_out;
      return run_orient(orient_options);
    }
    if (*edit) {
      edit_options.work = edit_work, edit_options.out = edit_out;
      if (edit_strands) edit_options.strands = edit_strands;
      return run_edit(edit_options, edit_json);
    }
    if (*pose) {
      pose_options.work = pose_work, pose_options.out = pose_out, pose_options.groom = pose_groom;
      return run_pose(pose_options, pose_json);
    }
    if (batch.parsed()) return batch.run();
    if (*render) {
      render_options.strands = render_strands, render_options.mesh = render_mesh;
      render_options.scene = render_scene, render_options.out = render_out;
      return run_render(render_options);
    }
  } catch (const std::exception&) {
    const nf::Failure f = nf::current_failure();
    std::cerr << "nf_gpu: " << f.line() << "\n";
    return f.exit_code;
  }
  return 0;
}
