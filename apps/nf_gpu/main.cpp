// nf_gpu: the command line. Parsing and printing only; the work lives in engine/.
#include <CLI/CLI.hpp>

#include <fstream>
#include <iostream>

#include "engine/bench/suites.hpp"
#include "engine/core/error.hpp"
#include "engine/core/json.hpp"
#include "engine/core/log.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gradcheck/catalog.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/io/mesh.hpp"
#include "engine/metrics/strand_metrics.hpp"
#include "engine/metrics/surface_metrics.hpp"
#include "engine/synth/preview.hpp"
#include "engine/orient/scene_orientation.hpp"
#include "engine/pipeline/stages.hpp"
#include "engine/synth/synth_scene.hpp"

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

struct MetricsOptions {
  std::string pred, gt, outer, mesh, reference;
  double fscore_mm = 5.0;
  double scale = 1.0;
  std::uint32_t strands = 100000, points = 100;
  unsigned seed = 1;
  bool json_out = false;
};

int run_surface_metrics(const MetricsOptions& o) {
  const auto m = nf::metrics::surface_metrics(nf::io::read_mesh(o.mesh), nf::io::read_mesh(o.reference), o.scale, o.fscore_mm);
  const nf::json out{{"mesh", o.mesh}, {"reference", o.reference}, {"cm_per_unit", o.scale}, {"surface", nf::metrics::to_json(m)}};
  if (o.json_out) {
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  std::printf("%s against %s (%llu samples each, %g cm per unit)\n", o.mesh.c_str(), o.reference.c_str(),
              (unsigned long long)m.samples, o.scale);
  std::printf("  chamfer mm          mean %.4g  min %.4g  max %.4g\n", m.chamfer_mean_mm, m.chamfer_min_mm, m.chamfer_max_mm);
  std::printf("  accuracy mm         %.4g\n  completeness mm     %.4g\n", m.accuracy_mm, m.completeness_mm);
  std::printf("  normal consistency  %.4f\n", m.normal_consistency);
  std::printf("  F-score at %g mm    precision %.2f  recall %.2f  F %.2f\n", m.fscore_threshold_mm, m.precision, m.recall, m.fscore);
  return 0;
}

int run_metrics(const MetricsOptions& o) {
  if (!o.mesh.empty() || !o.reference.empty()) {
    if (o.mesh.empty() || o.reference.empty()) throw nf::UsageError("surface metrics need both --mesh and --ref");
    return run_surface_metrics(o);
  }
  if (o.pred.empty()) throw nf::UsageError("metrics need --pred (strands) or --mesh and --ref (surfaces)");
  const auto pred = nf::metrics::sample_strands(nf::io::read_strands(o.pred), o.strands, o.points, o.seed);
  nf::json out{{"pred", o.pred}, {"strands", pred.strands}, {"points_per_strand", pred.points},
               {"cm_per_unit", o.scale}, {"consistency", nf::metrics::to_json(nf::metrics::consistency_metrics(pred, o.scale))}};
  if (!o.gt.empty()) {
    const auto gt = nf::metrics::sample_strands(nf::io::read_strands(o.gt), o.strands, o.points, o.seed + 1);
    out["gt"] = o.gt;
    out["match"] = nf::metrics::to_json(nf::metrics::match_scores(pred, gt, nf::metrics::default_thresholds(), o.scale));
  }
  if (!o.outer.empty())
    out["tips_to_outer"] = nf::metrics::to_json(nf::metrics::tip_chamfer(pred, nf::io::read_mesh(o.outer), o.scale));
  if (o.json_out) {
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  std::cout << "strands: " << pred.strands << " sampled from " << o.pred << " (" << pred.points << " points each, "
            << o.scale << " cm per unit)\n";
  for (const auto& [key, value] : out["consistency"].items()) std::printf("  %-28s %12.6g\n", key.c_str(), value.get<double>());
  if (out.contains("match")) {
    std::cout << "against " << o.gt << ":\n  distance  angle  directed  precision  recall  F-score\n";
    for (const auto& m : out["match"])
      std::printf("  %5.1f cm %5.0f°  %-8s  %9.2f  %6.2f  %7.2f\n", m["distance_cm"].get<double>(),
                  m["angle_deg"].get<double>(), m["directed"].get<bool>() ? "yes" : "no", m["precision"].get<double>(),
                  m["recall"].get<double>(), m["fscore"].get<double>());
  }
  if (out.contains("tips_to_outer"))
    std::printf("strand tips against %s: two-way chamfer %.4g mm\n", o.outer.c_str(),
                out["tips_to_outer"]["two_way_mm"].get<double>());
  return 0;
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

int run_orient(const nf::orient::SceneOrientationOptions& options) {
  nf::gpu::Context context;
  const auto files = nf::orient::write_scene_orientations(context, options);
  std::printf("orient: %zu views -> %s\n", files.size() / 2, options.out.string().c_str());
  return 0;
}

int run_render(const nf::synth::PreviewOptions& options) {
  const auto r = nf::synth::render_previews(options);
  std::printf("render: %zu views -> %s (strand radius %.4g scene units, coloured by %s, %.1f s)\n", r.files.size(),
              options.out.string().c_str(), r.strand_radius, r.coloring.c_str(), r.seconds);
  return 0;
}

int run_bench(const nf::bench::Options& options, const std::string& json_path, bool profile) {
  nf::gpu::Context context;
  const json records = nf::bench::run_suite(context, options);
  std::cout << records.dump(2) << "\n";
  if (!json_path.empty()) nf::bench::write_records(json_path, records);
  if (profile) print_profile(context);
  return 0;
}

int run_reconstruct(const nf::pipeline::ReconstructOptions& options, bool as_json, bool profile) {
  nf::gpu::Context context;
  const auto outcomes = nf::pipeline::reconstruct(context, options);
  if (profile) print_profile(context);
  if (as_json) {
    json out = json::array();
    for (const auto& o : outcomes)
      out.push_back({{"stage", o.name}, {"ran", o.ran}, {"seconds", o.seconds}, {"summary", o.summary}});
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  for (const auto& o : outcomes)
    std::printf("%-10s %s%s\n", o.name.c_str(), o.ran ? "ran in " : "unchanged, skipped",
                o.ran ? (std::to_string(o.seconds) + " s").c_str() : "");
  std::printf("outputs in %s\n", options.work.string().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"nf_gpu: furless body mesh and strand-based fur from multi-view photos, on Vulkan compute"};
  app.require_subcommand(1);
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

  MetricsOptions metrics_options;
  auto* metrics = app.add_subcommand("metrics", "strand metrics (paper supplementary): consistency, and P/R/F against ground truth");
  metrics->add_option("--pred", metrics_options.pred, "predicted strands (.hair, .ply, .obj, .usda)")->check(CLI::ExistingFile);
  metrics->add_option("--outer", metrics_options.outer, "outer surface mesh: two-way chamfer with the strand tips")->check(CLI::ExistingFile);
  metrics->add_option("--mesh", metrics_options.mesh, "surface metrics: this mesh (.ply, .obj)...")->check(CLI::ExistingFile);
  metrics->add_option("--ref", metrics_options.reference, "...against this reference mesh")->check(CLI::ExistingFile);
  metrics->add_option("--fscore-mm", metrics_options.fscore_mm, "surface F-score distance in mm (default 5)")->check(CLI::PositiveNumber);
  metrics->add_option("--gt", metrics_options.gt, "ground-truth strands")->check(CLI::ExistingFile);
  metrics->add_option("--scale", metrics_options.scale, "cm per scene unit (default 1)")->check(CLI::PositiveNumber);
  metrics->add_option("--strands", metrics_options.strands, "strands sampled from each side (default 100000)");
  metrics->add_option("--points", metrics_options.points, "points per resampled strand (default 100)");
  metrics->add_option("--seed", metrics_options.seed, "sampling seed");
  metrics->add_flag("--json", metrics_options.json_out, "machine-readable output");

  nf::synth::SynthOptions synth_options;
  std::string synth_out;
  auto* synth = app.add_subcommand("synth", "a procedural furry quadruped with ground truth (images, masks, cameras, strands, meshes)");
  synth->add_option("--animal", synth_options.animal, "cat, dog, fox, panda, tiger or lion")
      ->check(CLI::IsMember({"cat", "dog", "fox", "panda", "tiger", "lion"}));
  synth->add_option("--views", synth_options.views, "number of views, on two camera rings (default 36)")->check(CLI::Range(1, 10000));
  synth->add_option("--res", synth_options.resolution, "image width and height in pixels (default 512)")->check(CLI::Range(8, 8192));
  synth->add_option("--seed", synth_options.seed, "varies proportions, pose, fur and placement (default 1)");
  synth->add_option("--strands", synth_options.strands, "ground-truth strands (default 100000)")->check(CLI::Range(1, 20000000));
  synth->add_option("--spp-axis", synth_options.samples_per_axis, "anti-aliasing: s x s samples per pixel (default 3)")->check(CLI::Range(1, 16));
  synth->add_option("--out", synth_out, "output folder (must be new, or an earlier synth scene with --overwrite)")->required();
  synth->add_flag("--overwrite", synth_options.overwrite, "replace an earlier synth scene in --out");

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
  auto* reconstruct = app.add_subcommand("reconstruct", "the method stage by stage (cached and resumable): surface (neus), ...");
  reconstruct->add_option("--scene", reconstruct_scene, "scene folder or transforms.json (any format nf_gpu reads)")->required();
  reconstruct->add_option("--out", reconstruct_out, "WORK folder: one sub-folder per stage (created if needed)")->required();
  reconstruct->add_option("--quality", reconstruct_options.quality, "draft, default or paper (default: default)")
      ->check(CLI::IsMember({"draft", "default", "paper"}));
  reconstruct->add_option("--from", reconstruct_options.run.from, "rerun from this stage even when unchanged");
  reconstruct->add_option("--to", reconstruct_options.run.to, "stop after this stage");
  reconstruct->add_option("--set", reconstruct_options.settings, "override a stage setting: stage.key=value (repeatable)");
  reconstruct->add_flag("--json", reconstruct_json, "machine-readable summary");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : int(nf::ExitCode::Usage);
  }

  try {
    if (*info) return run_info(info_json);
    if (*gradcheck) return run_gradcheck(kernel_name, gradcheck_json);
    if (*bench) return run_bench(bench_options, bench_json, profile);
    if (*metrics) return run_metrics(metrics_options);
    if (*synth) return run_synth(synth_out, synth_options);
    if (*reconstruct) {
      reconstruct_options.scene = reconstruct_scene, reconstruct_options.work = reconstruct_out;
      return run_reconstruct(reconstruct_options, reconstruct_json, profile);
    }
    if (*orient) {
      orient_options.scene = orient_scene, orient_options.out = orient_out;
      return run_orient(orient_options);
    }
    if (*render) {
      render_options.strands = render_strands, render_options.mesh = render_mesh;
      render_options.scene = render_scene, render_options.out = render_out;
      return run_render(render_options);
    }
  } catch (const nf::Error& e) {
    std::cerr << "nf_gpu: error: " << e.what() << "\n";
    return int(e.code());
  } catch (const std::exception& e) {
    std::cerr << "nf_gpu: internal error: " << e.what() << "\n";
    return int(nf::ExitCode::DeviceOrInternal);
  }
  return 0;
}
