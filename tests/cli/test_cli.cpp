// The nf_gpu command line as a user runs it: outputs, JSON records and exit codes.
#include <doctest/doctest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <thread>

#include "engine/core/color.hpp"
#include "engine/core/json.hpp"
#include "engine/fur/roots.hpp"
#include "engine/fur/strand_colors.hpp"
#include "engine/io/file_frame.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/strand_files.hpp"
#include "tests/support/nf_process.hpp"

using nf::test::Result;
using nf::test::run;
using nf::test::slurp;
using nf::test::spawn;
using nf::test::stage_names;
using nf::test::wait_exit;
using nf::test::wait_for;

TEST_CASE("nf_gpu info names the device, as text and as JSON") {
  const Result text = run("info");
  CHECK(text.code == 0);
  CHECK(text.output.find("device: ") != std::string::npos);
  CHECK(text.output.find("<- chosen") != std::string::npos);
  const Result j = run("info --json");
  REQUIRE(j.code == 0);
  const nf::json info = nf::json::parse(j.output);
  CHECK(!info["chosen"]["name"].get<std::string>().empty());
  CHECK(info["chosen"]["limits"]["max_storage_buffer_range"].get<std::uint64_t>() > 0);
  CHECK(info["devices"].size() >= 1);
}

TEST_CASE("nf_gpu gradcheck prints one passing row per kernel, case, check and array") {
  const Result r = run("gradcheck --kernel splat/segment_gaussian");
  CHECK(r.code == 0);
  CHECK(r.output.find("max rel") != std::string::npos);
  CHECK(r.output.find("zero_length") != std::string::npos);
  CHECK(r.output.find("FAIL") == std::string::npos);
  CHECK(r.output.find("all checks passed") != std::string::npos);
  CHECK(r.output.find("validation") == std::string::npos);  // ctest runs nf_gpu with NF_VALIDATION=1
  const Result bad = run("gradcheck --kernel no/such_kernel");
  CHECK(bad.code == 2);
  CHECK(bad.output.find("splat/segment_gaussian") != std::string::npos);  // lists what exists
}

TEST_CASE("nf_gpu bench --suite core writes the roofline records") {
  const auto path = std::filesystem::temp_directory_path() / "nf_test_bench_core.json";
  std::filesystem::remove(path);
  const Result r = run("bench --suite core --quick --json " + path.string());
  REQUIRE(r.code == 0);
  CHECK(r.output.find("validation") == std::string::npos);
  std::ifstream in(path);
  const nf::json records = nf::json::parse(in);
  REQUIRE(records.is_array());
  std::set<std::string> cases;
  for (const auto& rec : records) {
    for (const char* key : {"suite", "case", "device", "params", "repeats", "seconds", "metrics", "peak_device_bytes"})
      CHECK(rec.contains(key));
    CHECK(rec["seconds"]["median"].get<double>() > 0);
    cases.insert(rec["case"].get<std::string>());
  }
  for (const char* c : {"copy_transfer", "copy_shader", "fma_f32", "dispatch_latency", "submit_latency",
                        "radix_sort_kv32", "std_sort_kv32", "exclusive_scan_u32", "reduce_sum_u32"})
    CHECK(cases.count(c) == 1);
  for (const auto& rec : records) {
    if (rec["case"] == "radix_sort_kv32") {
      CHECK(rec["metrics"]["mismatches_vs_std_stable_sort"].get<std::uint64_t>() == 0);
      CHECK(rec["metrics"]["speedup_vs_std_sort"].get<double>() > 0);
    }
    if (rec["case"] == "fma_f32") CHECK(rec["metrics"]["GFLOPs_wall"].get<double>() > 0);
  }
  std::filesystem::remove(path);
  // A file that is not bench records is never replaced, and the refusal comes before the run.
  std::ofstream(path) << "my notes";
  const Result foreign = run("bench --suite core --quick --json " + path.string());
  CHECK(foreign.code == 1);
  CHECK(foreign.output.find("never replaced") != std::string::npos);
  std::ifstream notes(path);
  CHECK(std::string(std::istreambuf_iterator<char>(notes), {}) == "my notes");
  std::filesystem::remove(path);
}

TEST_CASE("without any Vulkan driver the error says which Debian package to install") {
  // Point the loader at no driver at all (and no layers), as on a machine without mesa-vulkan-drivers.
  const Result r = run("info", "VK_ICD_FILENAMES=/nonexistent.json VK_DRIVER_FILES=/nonexistent.json NF_VALIDATION=0");
  CHECK(r.code == 3);
  CHECK(r.output.find("mesa-vulkan-drivers") != std::string::npos);
}

TEST_CASE("nf_gpu metrics scores strand files and names bad input") {
  const auto dir = std::filesystem::temp_directory_path();
  std::vector<float> xyz;
  for (int i = 0; i < 30; ++i)
    for (int p = 0; p < 10; ++p) xyz.insert(xyz.end(), {float(i), 0.1f * p, 0.f});
  nf::io::write_hair(dir / "nf_cli_a.hair", nf::io::StrandSet::uniform(30, 10, xyz));
  const Result r = run("metrics --pred " + (dir / "nf_cli_a.hair").string() + " --gt " + (dir / "nf_cli_a.hair").string() +
                       " --scale 2 --json");
  REQUIRE(r.code == 0);
  const nf::json m = nf::json::parse(r.output);
  CHECK(m["strands"] == 30);
  CHECK(m["consistency"]["length_mean_cm"].get<double>() == doctest::Approx(1.8));
  for (const auto& score : m["match"]) CHECK(score["fscore"].get<double>() == doctest::Approx(100));
  std::ofstream(dir / "nf_cli_bad.hair") << "HAIR but truncated";
  const Result bad = run("metrics --scale 1 --pred " + (dir / "nf_cli_bad.hair").string());
  CHECK(bad.code == 1);
  CHECK(bad.output.find("nf_cli_bad.hair") != std::string::npos);
  CHECK(run("metrics --pred /nonexistent.hair").code == 2);
  std::filesystem::remove(dir / "nf_cli_a.hair");
  std::filesystem::remove(dir / "nf_cli_bad.hair");
}

TEST_CASE("nf_gpu metrics compares meshes") {
  const auto dir = std::filesystem::temp_directory_path();
  nf::geometry::Mesh quad;
  quad.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  quad.triangles = {0, 1, 2, 0, 2, 3};
  nf::io::write_mesh(dir / "nf_cli_quad.ply", quad);
  for (std::size_t i = 2; i < quad.positions.size(); i += 3) quad.positions[i] = 0.1f;  // 0.1 units higher
  nf::io::write_mesh(dir / "nf_cli_quad_up.obj", quad);
  const Result r = run("metrics --mesh " + (dir / "nf_cli_quad_up.obj").string() + " --ref " +
                       (dir / "nf_cli_quad.ply").string() + " --scale 10 --json");  // 10 cm per unit: 10 mm apart
  REQUIRE(r.code == 0);
  const nf::json m = nf::json::parse(r.output);
  CHECK(m["surface"]["accuracy_mm"].get<double>() == doctest::Approx(10).epsilon(0.02));
  CHECK(run("metrics --mesh " + (dir / "nf_cli_quad.ply").string()).code == 2);  // --ref missing
  const Result mesh_as_strands = run("metrics --scale 1 --pred " + (dir / "nf_cli_quad.ply").string());
  CHECK(mesh_as_strands.code == 1);
  CHECK(mesh_as_strands.output.find("this is a mesh (it has faces), not strands") != std::string::npos);
  std::filesystem::remove(dir / "nf_cli_quad.ply");
  std::filesystem::remove(dir / "nf_cli_quad_up.obj");
}

TEST_CASE("nf_gpu metrics never guesses a unit, and takes thresholds with units") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "nf_cli_units";
  fs::remove_all(dir);
  fs::create_directories(dir / "result");
  // 30 strands 1 cm apart in metres (0.01 units); the prediction is the truth shifted by 5 mm.
  std::vector<float> truth, shifted;
  for (int i = 0; i < 30; ++i)
    for (int p = 0; p < 10; ++p) {
      truth.insert(truth.end(), {0.01f * float(i), 0.001f * float(p), 0.f});
      shifted.insert(shifted.end(), {0.01f * float(i), 0.001f * float(p), 0.005f});
    }
  nf::io::write_hair(dir / "result" / "pred.hair", nf::io::StrandSet::uniform(30, 10, shifted));
  nf::io::write_hair(dir / "truth.hair", nf::io::StrandSet::uniform(30, 10, truth));
  const std::string files = " --pred " + (dir / "result" / "pred.hair").string() + " --gt " + (dir / "truth.hair").string();
  const Result unknown = run("metrics" + files);
  CHECK(unknown.code == 2);
  CHECK(unknown.output.find("--scale") != std::string::npos);  // says what to do
  // Metres: 5 mm apart is a match at 2 cm, not at 2 mm.
  const Result cm = run("metrics --json --scale 100" + files);
  REQUIRE(cm.code == 0);
  CHECK(nf::json::parse(cm.output)["match"][0]["fscore"].get<double>() == doctest::Approx(100));
  const Result mm = run("metrics --json --scale 100 --thresholds mm" + files);
  REQUIRE(mm.code == 0);
  const nf::json mm_json = nf::json::parse(mm.output);
  CHECK(mm_json["match"][0]["distance_cm"].get<double>() == doctest::Approx(0.2));
  CHECK(mm_json["match"][0]["fscore"].get<double>() == doctest::Approx(0));
  // A scale.json beside the result says the unit; --thresholds takes units per entry.
  std::ofstream(dir / "result" / "scale.json") << R"({"cm_per_unit": 100})";
  const Result declared = run("metrics --json --thresholds 6mm:20,1cm:30" + files);
  REQUIRE(declared.code == 0);
  const nf::json d = nf::json::parse(declared.output);
  CHECK(d["cm_per_unit"].get<double>() == 100);
  CHECK(d["scale_source"].get<std::string>().find("scale.json") != std::string::npos);
  CHECK(d["match"][0]["fscore"].get<double>() == doctest::Approx(100));
  CHECK(run("metrics --thresholds 2:20" + files).code == 2);  // no unit
  fs::remove_all(dir);
}

TEST_CASE("usage errors exit with 2; help and folder messages say what is wrong") {
  const Result bare = run("");
  CHECK(bare.code == 2);
  CHECK(bare.output.find("Subcommands:") != std::string::npos);  // the help, not "A subcommand is required"
  CHECK(run("no-such-command").code == 2);
  CHECK(run("bench --suite no-such-suite").code == 2);
  CHECK(run("--help").code == 0);
  const Result help = run("help");
  CHECK(help.code == 0);
  CHECK(help.output.find("reconstruct") != std::string::npos);
  CHECK(run("help pose").output.find("--groom") != std::string::npos);
  const Result typo = run("help pos");
  CHECK(typo.code == 2);
  CHECK(typo.output.find("did you mean 'pose'") != std::string::npos);
  // Folders: --out under a file, --work that does not exist.
  const auto file = std::filesystem::temp_directory_path() / "nf_cli_a_file";
  std::ofstream(file) << "x";
  const Result under = run("reconstruct --scene " + file.parent_path().string() + " --out " + (file / "sub").string() + " --set knowledge.preset=cat");
  CHECK(under.code == 1);
  CHECK(under.output.find(file.string() + " is a file, not a folder") != std::string::npos);
  const Result no_work = run("edit --work /nonexistent/work --out " + (file.parent_path() / "nf_cli_edit").string());
  CHECK(no_work.code == 1);
  CHECK(no_work.output.find("--work /nonexistent/work: no such folder") != std::string::npos);
  std::filesystem::remove(file);
}

TEST_CASE("nf_gpu synth, orient and render chain on a tiny scene; bad views exit with 2") {
  const auto dir = std::filesystem::temp_directory_path() / "nf_cli_chain";
  std::filesystem::remove_all(dir);
  const std::string scene = (dir / "scene").string();
  const Result s = run("synth --animal fox --views 2 --res 48 --strands 1500 --spp-axis 1 --out " + scene);
  REQUIRE(s.code == 0);
  CHECK(s.output.find("synth: fox, 2 views at 48x48") != std::string::npos);
  CHECK(run("synth --animal fox --views 2 --res 48 --strands 1500 --out " + scene).code == 2);  // exists, no --overwrite
  const Result o = run("orient --scene " + scene + " --out " + (dir / "orient").string());
  REQUIRE(o.code == 0);
  CHECK(std::filesystem::exists(dir / "orient" / "001.exr"));
  CHECK(std::filesystem::exists(dir / "orient" / "001.png"));
  CHECK(run("orient --scene " + scene + " --out " + (dir / "orient").string() + " --views 7").code == 2);
  CHECK(!std::filesystem::exists(dir / "orient" / "truth_agreement.json"));  // no true orientation in this scene
  // With the true orientation written, orient scores its maps against it.
  const std::string truthful = (dir / "truthful").string();
  REQUIRE(run("synth --animal fox --views 2 --res 192 --strands 60000 --spp-axis 2 --true-orientation --out " + truthful).code == 0);
  CHECK(std::filesystem::exists(dir / "truthful" / "gt" / "orientation" / "000.exr"));
  const Result t = run("orient --scene " + truthful + " --out " + (dir / "orient_truth").string());
  REQUIRE(t.code == 0);
  CHECK(t.output.find("median err") != std::string::npos);
  const nf::json agreement = nf::json::parse(slurp(dir / "orient_truth" / "truth_agreement.json"));
  REQUIRE(agreement["views"].size() == 2);
  for (const nf::json& v : agreement["views"]) {
    CHECK(v["pixels"].get<int>() > 0);
    CHECK(v["median_error_deg"].get<double>() < 45.0);  // better than chance (45 degrees)
  }
  const Result r = run("render --strands " + scene + "/gt/strands.hair --mesh " + scene + "/gt/bald.ply --scene " + scene +
                       " --views 1 --spp-axis 1 --out " + (dir / "render").string());
  CHECK(r.code == 0);
  CHECK(std::filesystem::exists(dir / "render" / "001.png"));
  CHECK(run("synth --animal unicorn --out " + (dir / "u").string()).code == 2);
  std::filesystem::remove_all(dir);
}

TEST_CASE("render and orient never write into the scene nor replace a file nf_gpu did not write") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "nf_cli_guard";
  fs::remove_all(dir);
  const std::string scene = (dir / "scene").string();
  REQUIRE(run("synth --animal fox --views 2 --res 32 --strands 500 --spp-axis 1 --out " + scene).code == 0);
  const auto bytes = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string photo = bytes(dir / "scene" / "images" / "001.png"), mask = bytes(dir / "scene" / "masks" / "001.png");
  const std::string render = "render --strands " + scene + "/gt/strands.hair --mesh " + scene + "/gt/bald.ply --scene " +
                             scene + " --views 1 --spp-axis 1 --out ";
  const std::string orient = "orient --scene " + scene + " --views 1 --out ";
  fs::create_directory_symlink(dir / "scene" / "masks", dir / "masks_link");
  for (const std::string& command : {render, orient}) {
    INFO(command);
    for (const fs::path& inside : {dir / "scene" / "images", dir / "scene" / "masks", dir / "other" / ".." / "scene" / "masks",
                                   dir / "masks_link"}) {
      const Result r = run(command + inside.string());
      CHECK(r.code == 2);
      CHECK(r.output.find("inside the scene folder") != std::string::npos);
    }
    // A folder of the user's with a file of the name nf_gpu would write: refused, file kept.
    fs::create_directories(dir / "mine");
    std::ofstream(dir / "mine" / "001.png") << "my picture";
    const Result theirs = run(command + (dir / "mine").string());
    CHECK(theirs.code == 1);
    CHECK(theirs.output.find("was not written by nf_gpu") != std::string::npos);
    CHECK(bytes(dir / "mine" / "001.png") == "my picture");
    fs::remove_all(dir / "mine");
    // Its own earlier output is replaced; an --out that is a file is bad input.
    CHECK(run(command + (dir / "out").string()).code == 0);
    CHECK(run(command + (dir / "out").string()).code == 0);
    const Result file = run(command + (dir / "scene" / "transforms.json").string());
    CHECK(file.code != 0);
    fs::remove_all(dir / "out");
  }
  CHECK(bytes(dir / "scene" / "images" / "001.png") == photo);
  CHECK(bytes(dir / "scene" / "masks" / "001.png") == mask);
  std::ofstream(dir / "a_file") << "x";
  const Result file = run(orient + (dir / "a_file").string());
  CHECK(file.code == 1);
  CHECK(file.output.find("is an existing file") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("nf_gpu reconstruct: the surface stage on a small synthetic scene, cached, with clear refusals") {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "nf_cli_reconstruct";
  fs::remove_all(root);
  const fs::path scene = root / "scene", work = root / "work";
  REQUIRE(run("synth --animal cat --views 8 --res 64 --strands 4000 --spp-axis 1 --out " + scene.string()).code == 0);
  const std::string tiny = " --quality draft --set neus.steps=12 --set neus.rays=128 --set neus.samples_per_ray=16 --set neus.fine_samples=8"
                           " --set neus.hull_fit_steps=5 --set neus.mesh_resolution=48 --set neus.hull_resolution=48";
  // The knowledge stage needs a source: without one the run stops before any stage, naming the ways.
  const Result unsourced = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny);
  CHECK(unsourced.code == 2);
  CHECK(unsourced.output.find("knowledge.preset=NAME (presets: cat, dog") != std::string::npos);
  CHECK(unsourced.output.find("knowledge.vlm=URL") != std::string::npos);
  CHECK_FALSE(fs::exists(work));
  const Result first = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + " --to neus");
  INFO(first.output);
  REQUIRE(first.code == 0);
  for (const char* f : {"neus/outer.ply", "neus/model.nfwt", "neus/normalisation.json", "neus/metrics.json",
                        "neus/training.jsonl", "neus/stage.json", "neus/renders/007_rgb.png", "neus/renders/007_depth.exr"})
    CHECK_MESSAGE(fs::exists(work / f), f);
  const nf::geometry::Mesh mesh = nf::io::read_mesh(work / "neus" / "outer.ply");
  CHECK(mesh.triangle_count() > 100);
  std::ifstream metrics(work / "neus" / "metrics.json");
  const nf::json m = nf::json::parse(metrics);
  CHECK(m["steps"] == 12);
  CHECK(m.contains("ground_truth"));  // a synth scene: chamfer against gt/outer.ply
  CHECK(m["held_out"]["views"].size() == 1);

  const Result again = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + " --to neus --json");
  REQUIRE(again.code == 0);
  REQUIRE(again.output.find('[') != std::string::npos);
  const nf::json outcome = nf::test::json_of(again);
  CHECK(outcome[0]["stage"] == "neus");
  CHECK(outcome[0]["ran"] == false);  // unchanged: skipped
  CHECK_FALSE(outcome[0].contains("kept"));
  // --to a later stage with other settings for neus, none of them named: the cached surface is
  // kept (minutes of work), saying which settings differ and how to remake it.
  const Result later = run("reconstruct --scene " + scene.string() + " --out " + work.string() + " --quality draft --set body.samples=2000"
                           " --set body.hypothesis_steps=8 --set body.global_steps=10 --set body.pose_steps=20 --set body.offset_steps=10"
                           " --set body.preview_views=1 --to body --json");
  INFO(later.output);
  REQUIRE(later.code == 0);
  const nf::json kept = nf::test::json_of(later);
  CHECK(kept[0]["ran"] == false);
  CHECK(kept[0]["kept"].get<std::string>().find("made with other settings (") != std::string::npos);
  CHECK(kept[0]["kept"].get<std::string>().find("--from neus remakes it") != std::string::npos);
  CHECK(m == nf::json::parse(std::ifstream(work / "neus" / "metrics.json")));  // the surface is the one made above
  fs::remove_all(work / "body");  // the body stage below starts from nothing
  // Named, the setting reruns the stage, saying what changed (and a few views get a warning).
  const Result named = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + " --set neus.steps=13 --to neus");
  REQUIRE(named.code == 0);
  CHECK(named.output.find("runs again, what it was made from changed: training.steps 12 -> 13") != std::string::npos);
  REQUIRE(run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + " --to neus").code == 0);  // back to 12 steps

  // The body stage on the cached surface: its files, labels on M_NeuS, ground-truth figures.
  const std::string body = " --set body.samples=2000 --set body.hypothesis_steps=8 --set body.global_steps=10"
                           " --set body.pose_steps=20 --set body.offset_steps=10 --set body.preview_views=1";
  const Result fitted = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + body + " --to body --json");
  INFO(fitted.output);
  REQUIRE(fitted.code == 0);
  const nf::json stages = nf::test::json_of(fitted);
  CHECK(stages[0]["ran"] == false);  // neus: unchanged
  CHECK(stages[1]["stage"] == "body");
  for (const char* f : {"body/outer_regions.ply", "body/fitted.ply", "body/params.json", "body/eyes.json",
                        "body/animal_frame.json", "body/metrics.json", "body/previews/000.png"})
    CHECK_MESSAGE(fs::exists(work / f), f);
  const nf::geometry::Mesh labelled = nf::io::read_mesh(work / "body" / "outer_regions.ply");
  CHECK(labelled.regions.size() == labelled.vertex_count());
  // A 12-step surface is a blob: only the record's form is checked here (test_body_fit and the body
  // bench measure the accuracy itself).
  const nf::json& truth = stages[1]["summary"]["ground_truth"];
  CHECK(truth["accuracy"].get<double>() >= 0.0);
  CHECK(truth["accuracy"].get<double>() <= 1.0);
  CHECK(truth["recall"].contains("tail"));
  CHECK(truth.contains("eye_error_mm"));
  const Result again_body = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + body + " --from body --to body --json");
  REQUIRE(again_body.code == 0);
  const nf::json rerun = nf::test::json_of(again_body);
  CHECK((rerun[0]["ran"] == false && rerun[1]["ran"] == true));  // --from body reruns body, not neus

  // The knowledge stage from a preset: the knowledge, world directions and the scale (the synth
  // scene declares its unit; the eyes' estimate is reported beside it).
  const Result known = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + body +
                           " --set knowledge.preset=cat --to knowledge --json");
  INFO(known.output);
  REQUIRE(known.code == 0);
  const nf::json all = nf::test::json_of(known);
  REQUIRE(all.size() == 3);
  CHECK((all[0]["ran"] == false && all[1]["ran"] == false && all[2]["ran"] == true));
  const nf::json& ks = all[2]["summary"];
  CHECK(ks["source"] == "preset:cat");
  CHECK(ks["scale"]["source"] == "scene");
  CHECK(ks["scale"]["cm_per_unit"].get<double>() == doctest::Approx(100.0));
  CHECK(ks["scale"]["from_eyes"].get<double>() > 0.0);
  CHECK(ks["ground_truth"].contains("scale_from_eyes_error"));
  // Both of the animal's scale cues, each with its spread, and their errors against the truth.
  REQUIRE(ks["scale"]["cues"].size() == 2);
  CHECK(ks["scale"]["cues"][0]["cue"] == "eyes");
  CHECK(ks["scale"]["cues"][1]["cue"] == "body length");
  CHECK(ks["scale"]["spread"].get<double>() == 0.0);  // the scene's unit is given
  CHECK(ks["ground_truth"]["scale_cue_errors"].contains("body length"));
  CHECK(nf::json::parse(slurp(work / "body" / "eyes.json"))["source"] == "fit");
  for (const char* f : {"knowledge/knowledge.json", "knowledge/directions_world.json", "knowledge/scale.json", "knowledge/metrics.json"})
    CHECK_MESSAGE(fs::exists(work / f), f);
  {
    // The eyes searched in the photos (in a copy, so the later stages keep their cache): found and
    // triangulated, or the fit's kept with the reason; the record says which.
    const fs::path eyes_work = work.string() + "-eyes";
    fs::remove_all(eyes_work);
    fs::copy(work, eyes_work, fs::copy_options::recursive);
    const Result eyes_run = run("reconstruct --scene " + scene.string() + " --out " + eyes_work.string() + tiny + body +
                                " --set body.photo_eyes=1 --from body --to body --json");
    INFO(eyes_run.output);
    REQUIRE(eyes_run.code == 0);
    const nf::json eyes = nf::json::parse(slurp(eyes_work / "body" / "eyes.json"));
    REQUIRE(eyes.contains("photos"));
    CHECK(eyes["photos"]["views_facing"].get<int>() >= 0);  // this scene's 64 px views may resolve no eye
    for (const char* side : {"left", "right"}) {
      CHECK((eyes["photos"][side]["position"].is_array() || eyes["photos"][side].contains("reason")));
      CHECK(eyes["photos"]["hypotheses"][side].is_array());  // every point the views agreed on, before the pair was chosen
    }
    CHECK((eyes["source"] == "photos" || eyes_run.output.find("the eyes were not found in the photos") != std::string::npos));
    fs::remove_all(eyes_work);
  }

  // Defur and frames on the cached stages: M_bald inside M_NeuS, its files, the masks, the roots.
  const std::string small = " --set defur.resolution=64 --set defur.preview_views=1 --set frames.roots=3000"
                            " --set fur.steps=12 --set fur.warm_steps=4 --set fur.batch=400 --set fur.strands=2500"
                            " --set fur.metric_strands=300 --set fur.resolution=64 --set fur.preview_views=1 --set fur.chamfer_queries=500"
                            " --set export.formats=usda,hair,ply,obj";
  const Result framed = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + body +
                            " --set knowledge.preset=cat" + small + " --json");
  INFO(framed.output);
  REQUIRE(framed.code == 0);
  const nf::json five = nf::test::json_of(framed);
  REQUIRE(five.size() == 7);
  CHECK((five[2]["ran"] == false && five[3]["stage"] == "defur" && five[4]["stage"] == "frames"));
  for (const char* f : {"defur/bald.ply", "defur/vertex_fur.npz", "defur/bald_sdf.npz", "defur/refit.ply", "defur/metrics.json",
                        "defur/nonbald_masks/007.png", "defur/previews/000.png", "frames/frames.npz", "frames/roots.npz",
                        "frames/metrics.json"})
    CHECK_MESSAGE(fs::exists(work / f), f);
  const nf::json& ds = five[3]["summary"];
  CHECK(ds["masks"]["views"] == 8);
  CHECK(ds["ground_truth"]["bald"]["chamfer_mm"]["mean"].get<double>() > 0.0);
  const nf::geometry::Mesh bald = nf::io::read_mesh(work / "defur" / "bald.ply");
  CHECK(bald.regions.size() == bald.vertex_count());
  CHECK(bald.triangle_count() > 100);
  const nf::json& fr = five[4]["summary"];
  CHECK(fr["roots"] == 3000);
  CHECK(fr["smoothness"]["mean_angle_deg"].get<double>() < 20.0);
  CHECK(fr["ground_truth"]["strands_compared"].get<int>() > 100);
  // The fur stage: a groom of the asked count (2,500 strands, not the 3,000 roots), its files, scores
  // against the synth scene's truth beside the baseline groom's.
  for (const char* f : {"fur/strands.hair", "fur/regions.npz", "fur/scale.json", "fur/model.nfwt", "fur/training.jsonl", "fur/metrics.json"})
    CHECK_MESSAGE(fs::exists(work / f), f);
  CHECK(nf::io::read_hair(work / "fur" / "strands.hair").strand_count() == 2500);
  const nf::json& fur_summary = five[5]["summary"];
  CHECK(fur_summary["strands"] == 2500);
  CHECK(fur_summary["skipped_steps"] == 0);
  // Photos of 64 px: the fur spans under a pixel (about half of the 128 px cat's 1.3), so no view's
  // image losses run, the log says so, and training stops after the 4 warm-up steps of the 12 (the
  // groom the knowledge, M_bald and M_NeuS give; fur.select=trained would run them all).
  CHECK(fur_summary["steps"] == 4);
  CHECK(framed.output.find("training stops after the 4 warm-up steps") != std::string::npos);
  // The selection weighs the 0-step groom against the warm-up's (no image step ran).
  CHECK((fur_summary["selection"]["kept"] == "0-step" || fur_summary["selection"]["kept"] == "warm-up"));
  CHECK(fur_summary["selection"].contains("0-step"));
  CHECK(fur_summary["selection"]["warm-up"]["against"] == "0-step");
  CHECK_FALSE(fur_summary["selection"].contains("trained"));
  // The length factors: one per region with roots, 1 where no step learned them, and the scale
  // they imply beside the knowledge's.
  REQUIRE(fur_summary["lengths"]["regions"].contains("body"));
  CHECK(fur_summary["lengths"]["regions"]["body"]["factor"].get<double>() == 1.0);
  CHECK(fur_summary["lengths"]["cm_per_unit_implied"].get<double>() == doctest::Approx(fur_summary["lengths"]["cm_per_unit_used"].get<double>()));
  CHECK(fur_summary["lengths"]["cm_per_unit_used"].get<double>() == doctest::Approx(nf::json::parse(std::ifstream(work / "fur" / "scale.json"))["cm_per_unit"].get<double>()));
  CHECK(fur_summary["views"]["fur_pixels_median"].get<double>() > 0.2);
  CHECK(fur_summary["views"]["fur_pixels_median"].get<double>() < 1.5);
  {
    // A batch or scoring count no view can rasterise is refused before the stage reads its inputs,
    // naming the setting, and the groom already made stays.
    const auto groom_time = fs::last_write_time(work / "fur" / "strands.hair");
    for (const char* too_many : {" --set fur.batch=10000000", " --set fur.score_strands=10000000"}) {
      const Result refused = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + body + " --set knowledge.preset=cat" +
                                 small + too_many + " --to fur");
      INFO(refused.output);
      CHECK(refused.code == 2);
      CHECK(refused.output.find(std::string(too_many).substr(7) + ": this device renders at most") != std::string::npos);
    }
    CHECK(fs::last_write_time(work / "fur" / "strands.hair") == groom_time);
  }
  CHECK(fur_summary["views"]["image_weight_mean"].get<double>() == 0.0);
  CHECK(fur_summary["views"]["views_without_image_losses"] == fur_summary["views"]["train"]);
  CHECK(framed.output.find("no photo resolves the fur") != std::string::npos);
  CHECK(fur_summary["groom"]["fscore"]["2cm_20deg"].get<double>() >= 0.0);
  CHECK(fur_summary["baseline"]["fscore"].contains("2mm_20deg"));
  CHECK(fur_summary["held_out"]["silhouette_iou"].get<double>() > 0.0);
  // The held-out views also score the baseline groom and, on a synth scene, the true groom.
  REQUIRE(fur_summary["held_out"].contains("baseline"));
  REQUIRE(fur_summary["held_out"].contains("truth"));
  CHECK(fur_summary["held_out"]["baseline"]["silhouette_iou"].get<double>() > 0.0);
  CHECK(fur_summary["held_out"]["truth"]["silhouette_iou"].get<double>() > 0.0);
  const Result metrics_cmd = run("metrics --pred " + (work / "fur" / "strands.hair").string() + " --strands 200 --json");
  CHECK(metrics_cmd.code == 0);  // scale.json beside the strands declares the unit
  {
    // A groom made at a wrong scale (--scene-scale 70 where the truth is 100) is judged at the
    // truth's: its straight baseline, grown 100/70 times too long in scene units, measures that much
    // longer in cm, and metrics.json says which scale judged it (in a copy: `work` keeps its cache).
    const fs::path scaled_work = work.string() + "-scaled";
    fs::remove_all(scaled_work);
    fs::copy(work, scaled_work, fs::copy_options::recursive);
    const Result scaled = run("reconstruct --scene " + scene.string() + " --out " + scaled_work.string() + tiny + body +
                              " --set knowledge.preset=cat" + small + " --scene-scale 70 --from knowledge --to fur");
    INFO(scaled.output);
    REQUIRE(scaled.code == 0);
    CHECK(scaled.output.find("the scores against the truth use the truth's") != std::string::npos);
    const nf::json wrong = nf::json::parse(slurp(scaled_work / "fur" / "metrics.json"));
    CHECK(nf::json::parse(slurp(scaled_work / "fur" / "scale.json"))["cm_per_unit"].get<double>() == 70.0);
    CHECK(wrong["ground_truth"]["cm_per_unit"].get<double>() == 100.0);
    const double ratio = wrong["baseline"]["consistency"]["length_mean_cm"].get<double>() /
                         fur_summary["baseline"]["consistency"]["length_mean_cm"].get<double>();
    CHECK(ratio == doctest::Approx(100.0 / 70.0).epsilon(0.1));
    fs::remove_all(scaled_work);
  }
  // The export stage: the groom in four formats and the rigged body, in metres, upright.
  for (const char* f : {"export/fur.usda", "export/fur.hair", "export/fur.ply", "export/fur.obj", "export/body.glb", "export/roots.npz",
                        "export/export.json", "export/turntable.png", "export/turntable_000.png"})
    CHECK_MESSAGE(fs::exists(work / f), f);
  CHECK(five[6]["summary"]["strands"] == 2500);
  const nf::io::StrandSet exported = nf::io::read_hair(work / "export" / "fur.hair");
  CHECK(exported.strand_count() == 2500);
  {
    // Colours from the photos on every strand (fur/colors.npz), in every format that holds them,
    // the same colour in each; scored against the synth scene's true colours.
    CHECK(fs::exists(work / "fur" / "colors.npz"));
    REQUIRE(exported.colors.size() == 3 * exported.point_count());
    CHECK(fur_summary["colors"]["controls"] == 3);
    CHECK(fur_summary["colors"]["strands_seen"].get<double>() > 0.0);
    CHECK(fur_summary["colors"]["ground_truth"]["delta_e_seen"]["mean"].get<double>() > 0.0);
    const nf::io::StrandSet ply = nf::io::read_strands_ply(work / "export" / "fur.ply");
    const nf::io::StrandSet usd = nf::io::read_strands_usda(work / "export" / "fur.usda");
    REQUIRE(ply.colors.size() == exported.colors.size());
    REQUIRE(usd.colors.size() == exported.colors.size());
    float lo = 1, hi = 0;
    std::size_t usd_off = 0, ply_off = 0;
    for (std::size_t i = 0; i < exported.colors.size(); ++i) {
      usd_off += std::abs(usd.colors[i] - exported.colors[i]) > 1e-5f * std::max(1.f, exported.colors[i]);
      ply_off += std::abs(nf::color::linear_to_srgb(ply.colors[i]) - nf::color::linear_to_srgb(exported.colors[i])) > 0.51f / 255.f;
      lo = std::min(lo, exported.colors[i]), hi = std::max(hi, exported.colors[i]);
    }
    CHECK(usd_off == 0);
    CHECK(ply_off == 0);  // 8-bit sRGB: within half a step
    CHECK(hi > lo);       // not one flat colour
    // The body's colours (fur/body_colors.npz): body.glb's COLOR_0, a colour per vertex, not flat.
    CHECK(fs::exists(work / "fur" / "body_colors.npz"));
    CHECK(fur_summary["colors"]["body"]["strands_seen"].get<double>() > 0.5);
    {
      const std::string glb = slurp(work / "export" / "body.glb");
      std::uint32_t n_json;
      std::memcpy(&n_json, glb.data() + 12, 4);
      const nf::json d = nf::json::parse(glb.substr(20, n_json));
      const auto& attributes = d["meshes"][0]["primitives"][0]["attributes"];
      REQUIRE(attributes.contains("COLOR_0"));
      const auto& a = d["accessors"][attributes["COLOR_0"].get<int>()];
      CHECK(a["count"] == d["accessors"][attributes["POSITION"].get<int>()]["count"]);
      const auto& view = d["bufferViews"][a["bufferView"].get<int>()];
      std::vector<float> rgb(3 * a["count"].get<std::size_t>());
      std::memcpy(rgb.data(), glb.data() + 20 + n_json + 8 + view["byteOffset"].get<std::size_t>(), 4 * rgb.size());
      // The fur stage's colours, vertex for vertex (clamped to glTF's [0, 1]).
      const nf::fur::StrandColors stored = nf::fur::read_strand_colors(work / "fur" / "body_colors.npz", rgb.size() / 3);
      REQUIRE(stored.rgb.size() == rgb.size());
      std::size_t differ = 0;
      for (std::size_t i = 0; i < rgb.size(); ++i) differ += std::abs(rgb[i] - std::clamp(stored.rgb[i], 0.f, 1.f)) > 1e-6f;
      CHECK(differ == 0);
      // Not one flat colour: the red channel varies across the vertices.
      float red_lo = 1, red_hi = 0;
      for (std::size_t v = 0; v < rgb.size() / 3; ++v) red_lo = std::min(red_lo, rgb[3 * v]), red_hi = std::max(red_hi, rgb[3 * v]);
      CHECK(red_hi > red_lo + 0.05f);
    }
    // index.html: every image and file it links is in the folder, with the figures measured.
    const std::string page = slurp(work / "export" / "index.html");
    std::size_t links = 0;
    for (const char* attribute : {"src=\"", "href=\""})
      for (std::size_t at = page.find(attribute); at != std::string::npos; at = page.find(attribute, at + 1)) {
        const std::size_t from = at + std::strlen(attribute), to = page.find('"', from);
        CHECK_MESSAGE(fs::exists(work / "export" / page.substr(from, to - from)), page.substr(from, to - from));
        ++links;
      }
    CHECK(links >= 6);
    CHECK(page.find("against the true strands") != std::string::npos);
    CHECK(page.find("colours against the true ones") != std::string::npos);
  }
  CHECK(exported.thickness.size() == exported.point_count());
  {  // Widths: a hair's diameter (mm -> m) at the root, not the fur layer's depth.
    const nf::json k = nf::json::parse(std::ifstream(work / "knowledge" / "knowledge.json"));
    const float hair_m = k["hair_diameter_mm"].get<float>() / 1000.f;
    std::uint32_t at_hair = 0;
    for (std::uint32_t i = 0; i < exported.strand_count(); ++i) at_hair += std::abs(exported.thickness[exported.offsets[i]] - hair_m) < 1e-3f * hair_m;
    CHECK(at_hair == exported.strand_count());
    CHECK(hair_m < 2e-4f);
  }
  CHECK(nf::io::read_strands_ply(work / "export" / "fur.ply").regions.size() == 2500);
  CHECK(nf::io::read_strands_obj(work / "export" / "fur.obj").strand_count() == 2500);
  CHECK(nf::io::read_strands_usda(work / "export" / "fur.usda").points == exported.points);
  // Every file states its frame; metrics brings an export file back over the scene through the
  // export.json beside it, so the exported groom scores against the stage's as itself.
  CHECK(nf::io::declared_frame(work / "export" / "fur.hair") == nf::io::FileFrame::exported);
  CHECK(nf::io::declared_frame(work / "export" / "fur.ply") == nf::io::FileFrame::exported);
  CHECK(nf::io::declared_frame(work / "export" / "body.glb") == nf::io::FileFrame::exported);
  CHECK(nf::io::declared_frame(work / "fur" / "strands.hair") == nf::io::FileFrame::scene);
  CHECK(nf::io::declared_frame(work / "defur" / "bald.ply") == nf::io::FileFrame::scene);
  {
    const Result across = run("metrics --pred " + (work / "export" / "fur.hair").string() + " --gt " + (work / "fur" / "strands.hair").string() +
                              " --strands 2500 --json");
    INFO(across.output);
    REQUIRE(across.code == 0);
    const nf::json scored = nf::test::json_of(across);
    CHECK(scored["frame"] == "scene");
    CHECK(scored["brought_back_from_export"].size() == 1);
    CHECK(scored["match"][0]["fscore"].get<double>() > 99.9);
    const Result bodies = run("metrics --mesh " + (work / "export" / "body.glb").string() + " --ref " + (work / "defur" / "bald.ply").string() + " --scale 100 --json");
    REQUIRE(bodies.code == 0);
    CHECK(nf::test::json_of(bodies)["surface"]["chamfer_mm"]["mean"].get<double>() < 0.01);
    fs::create_directories(root / "lone");
    fs::copy_file(work / "export" / "fur.hair", root / "lone" / "fur.hair", fs::copy_options::overwrite_existing);
    const Result lone = run("metrics --pred " + (root / "lone" / "fur.hair").string() + " --gt " + (work / "fur" / "strands.hair").string());
    CHECK(lone.code == 1);
    CHECK(lone.output.find("no export.json beside it") != std::string::npos);
  }
  const nf::io::Skeleton skeleton = nf::io::read_skeleton_gltf(work / "export" / "body.glb");
  const nf::geometry::Mesh body_glb = nf::io::read_mesh_gltf(work / "export" / "body.glb");
  CHECK(skeleton.joint_count() > 10);
  CHECK(body_glb.vertex_count() == bald.vertex_count());
  // Metres: the synth cat (1 unit = 1 m) keeps its size, standing on y = 0.
  float lowest = 1e9f, highest = -1e9f;
  for (std::size_t v = 0; v < body_glb.vertex_count(); ++v) lowest = std::min(lowest, body_glb.positions[3 * v + 1]), highest = std::max(highest, body_glb.positions[3 * v + 1]);
  CHECK(lowest == doctest::Approx(0.0).epsilon(1e-5));
  CHECK(highest > 0.1f);
  CHECK(highest < 1.0f);
  CHECK(framed.output.find("blender -b -P tools/blender/nf_gpu_import.py") == std::string::npos);  // --json prints JSON only

  // nf_gpu edit: the tail 1.5 times longer, the rest bit-identical; a shave; a density.
  const nf::io::StrandSet groom = nf::io::read_hair(work / "fur" / "strands.hair");
  std::vector<std::int32_t> regions;
  {
    nf::json k = nf::json::parse(std::ifstream(work / "knowledge" / "knowledge.json"));
    const double tail_cm = k["regions"]["tail"]["length_cm"].get<double>();
    const Result edit = run("edit --work " + work.string() + " --out " + (root / "edit_tail").string() + " --set tail.length_cm=" +
                            std::to_string(1.5 * tail_cm) + " --formats usda,hair,ply,obj --json");
    INFO(edit.output);
    REQUIRE(edit.code == 0);
    for (const char* f : {"fur.usda", "fur.hair", "fur.ply", "fur.obj", "body.glb", "roots.npz", "export.json", "edit.json", "scene_strands.hair"})
      CHECK_MESSAGE(fs::exists(root / "edit_tail" / f), f);
    const nf::io::StrandSet longer = nf::io::read_hair(root / "edit_tail" / "scene_strands.hair");
    REQUIRE(longer.strand_count() == groom.strand_count());
    // The same roots keep their colours through an edit.
    CHECK(nf::io::read_hair(root / "edit_tail" / "fur.hair").colors == exported.colors);
    // Regions of the groom: the stage's regions.npz (i4).
    const std::string npz = (work / "fur" / "regions.npz").string();
    const nf::json edit_record = nf::json::parse(std::ifstream(root / "edit_tail" / "edit.json"));
    CHECK(edit_record["edits"]["regions"]["tail"]["length_cm"].get<double>() == doctest::Approx(1.5 * tail_cm));
    const nf::io::StrandSet ply = nf::io::read_strands_ply(work / "export" / "fur.ply");  // regions per strand
    int tails = 0, identical = 0, others = 0, scaled = 0;
    for (std::uint32_t i = 0; i < groom.strand_count(); ++i) {
      const auto length = [](const nf::io::StrandSet& s, std::uint32_t strand) {
        double l = 0;
        for (std::uint32_t p = s.offsets[strand] + 1; p < s.offsets[strand + 1]; ++p)
          l += std::sqrt(std::pow(s.points[3 * p] - s.points[3 * p - 3], 2) + std::pow(s.points[3 * p + 1] - s.points[3 * p - 2], 2) +
                         std::pow(s.points[3 * p + 2] - s.points[3 * p - 1], 2));
        return l;
      };
      const bool same = std::equal(groom.points.begin() + 3 * groom.offsets[i], groom.points.begin() + 3 * groom.offsets[i + 1],
                                   longer.points.begin() + 3 * longer.offsets[i]);
      if (ply.regions[i] == 12) {  // tail
        ++tails;
        scaled += std::abs(length(longer, i) / length(groom, i) - 1.5) < 0.015;
      } else {
        ++others, identical += same;
      }
      regions.push_back(ply.regions[i]);
    }
    CHECK(tails > 0);
    CHECK(scaled == tails);
    CHECK(identical == others);
    // One result per folder: the same folder again with the default formats (USD and .hair); the
    // earlier edit's PLY and OBJ go, and the summary names only what this run wrote.
    const Result defaults = run("edit --work " + work.string() + " --out " + (root / "edit_tail").string());
    INFO(defaults.output);
    REQUIRE(defaults.code == 0);
    for (const char* f : {"fur.usda", "fur.hair", "edit.json"}) CHECK_MESSAGE(fs::exists(root / "edit_tail" / f), f);
    for (const char* f : {"fur.ply", "fur.obj"}) CHECK_MESSAGE(!fs::exists(root / "edit_tail" / f), f);
    CHECK(defaults.output.find("fur.hair   ") != std::string::npos);
    CHECK(defaults.output.find("fur.ply    the strands") == std::string::npos);
    // A file-size limit (SIGXFSZ): an error naming the file, nothing half-written left, the earlier
    // result untouched; and the temporary a killed run left is removed.
    const std::string before_hair = slurp(root / "edit_tail" / "fur.hair");
    std::ofstream(root / "edit_tail" / ".fur.usda.tmp999999999-1") << "half";  // beyond any pid
    const Result limited = run("edit --work " + work.string() + " --out " + (root / "edit_tail").string() + " --set tail.length_cm=9", "ulimit -f 16;");
    CHECK(limited.code == 1);
    CHECK(limited.output.find("file-size limit") != std::string::npos);
    CHECK(limited.output.find((root / "edit_tail").string()) != std::string::npos);
    for (const auto& e : fs::directory_iterator(root / "edit_tail"))
      CHECK_MESSAGE(e.path().filename().string().find(".tmp") == std::string::npos, e.path().string());
    CHECK(slurp(root / "edit_tail" / "fur.hair") == before_hair);
    // Ctrl-C during an edit: a message, 130, no partial file, the earlier result intact.
    {
      const fs::path log = root / "edit_sigint.txt";
      const pid_t pid = nf::test::spawn("edit --work " + work.string() + " --out " + (root / "edit_tail").string() + " --strands 3000000", log);
      std::this_thread::sleep_for(std::chrono::seconds(3));
      kill(pid, SIGINT);
      CHECK(nf::test::wait_exit(pid) == 130);
      CHECK_MESSAGE(slurp(log).find("edit: stopped on request; no partial file is left, but files this run had finished") != std::string::npos,
                    slurp(log));
      for (const auto& e : fs::directory_iterator(root / "edit_tail"))
        CHECK_MESSAGE(e.path().filename().string().find(".tmp") == std::string::npos, e.path().string());
      CHECK(slurp(root / "edit_tail" / "fur.hair") == before_hair);
    }
    const Result shave = run("edit --work " + work.string() + " --out " + (root / "edit_shave").string() + " --shave tail --set body.density=0.5 --formats usda,hair,ply");
    INFO(shave.output);
    REQUIRE(shave.code == 0);
    CHECK(shave.output.find("blender -b -P tools/blender/nf_gpu_import.py") != std::string::npos);
    CHECK(shave.output.find("open in a browser: ") != std::string::npos);
    CHECK(fs::exists(root / "edit_shave" / "index.html"));
    const nf::io::StrandSet shaved = nf::io::read_strands_ply(root / "edit_shave" / "fur.ply");
    int shaved_body = 0, groom_body = 0;
    for (std::uint16_t region : shaved.regions) {
      CHECK(region != 12);
      shaved_body += region == 14;
    }
    for (std::int32_t region : regions) groom_body += region == 14;
    CHECK(double(shaved_body) == doctest::Approx(0.5 * groom_body).epsilon(0.15));
    CHECK(run("edit --work " + work.string() + " --out " + (work / "inside").string() + " --shave tail").code == 2);
    CHECK(run("edit --work " + work.string() + " --out " + (root / "edit_bad").string() + " --set tial.length_cm=3").code == 2);
  }
  // nf_gpu pose: the head turned; the body moves where the head's joints own it, the groom with it.
  {
    const Result posed = run("pose --work " + work.string() + " --out " + (root / "posed").string() + " --set joint.head=0,40,0 --json");
    INFO(posed.output);
    REQUIRE(posed.code == 0);
    const nf::geometry::Mesh moved = nf::io::read_mesh_gltf(root / "posed" / "body.glb");
    REQUIRE(moved.vertex_count() == body_glb.vertex_count());
    int changed = 0;
    for (std::size_t i = 0; i < moved.positions.size(); ++i) changed += std::abs(moved.positions[i] - body_glb.positions[i]) > 1e-4f;
    CHECK(changed > 10);
    CHECK(changed < int(moved.positions.size()) / 2);
    CHECK(nf::io::read_hair(root / "posed" / "fur.hair").strand_count() == 2500);
    CHECK(nf::io::read_hair(root / "posed" / "fur.hair").colors == exported.colors);  // a pose moves strands, not colours
    CHECK(nf::io::read_skeleton_gltf(root / "posed" / "body.glb").joint_count() == skeleton.joint_count());
    const Result wrong = run("pose --work " + work.string() + " --out " + (root / "posed2").string() + " --set joint.hed=0,40,0");
    CHECK(wrong.code == 2);
    CHECK(wrong.output.find("joints: ") != std::string::npos);
    CHECK(wrong.output.find("did you mean 'head'") != std::string::npos);
    // A posed groom cannot be put back over the scene: refused, saying what to compare.
    const Result posed_metrics = run("metrics --pred " + (root / "posed" / "fur.hair").string() + " --gt " + (work / "fur" / "strands.hair").string());
    CHECK(posed_metrics.code == 1);
    CHECK(posed_metrics.output.find("posed groom") != std::string::npos);
    const Result no_groom = run("pose --work " + work.string() + " --out " + (root / "posed3").string() + " --groom " + (root / "no_edit").string() +
                                " --set joint.head=0,40,0");
    CHECK(no_groom.code == 1);
    CHECK(no_groom.output.find("--groom " + (root / "no_edit").string() + ": no such folder") != std::string::npos);
  }
  // The fur stage on the scene's truth (the bench's baseline (b) and ablations) with its curve of
  // scores against training time, over all 12 steps (select=trained: no 64 px photo resolves the
  // fur, so auto would stop after the warm-up).
  {
    const Result truthful = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + body + " --set knowledge.preset=cat" +
                                small + " --set fur.truth=all --set fur.curve_seconds=0.01 --set fur.select=trained --set fur.patch=40 --to fur --json");
    INFO(truthful.output);
    REQUIRE(truthful.code == 0);
    const nf::json runs = nf::test::json_of(truthful);
    REQUIRE(runs.size() == 6);
    const nf::json& ts = runs[5]["summary"];
    CHECK(ts["truth"] == "all");
    // Native-resolution patches (fur.patch=40): the views' targets went to disk and the groom was
    // scored on fixed patches of the held-out views (64 px views: more than one patch each).
    REQUIRE(ts["views"].contains("patches"));
    CHECK(ts["views"]["patches"]["size"] == 40);
    CHECK(ts["views"]["patches"]["bytes_on_disk"].get<double>() > 0);
    CHECK(ts["views"]["patches"]["held_out_patches"].get<int>() >= ts["views"]["held_out"].get<int>());
    CHECK(ts["views"]["patches"]["orientation_reliability"].get<double>() >= 0.0);
    CHECK(ts["roots_file"] == "fur/roots.npz");  // roots on the true body, not frames/roots.npz
    CHECK(nf::fur::read_roots(work / "fur" / "roots.npz").size() == 2500);
    CHECK(nf::io::read_hair(work / "fur" / "strands.hair").strand_count() == 2500);
    // The straight strands on the true body at the true lengths and directions (baseline (b)) are
    // nearer the truth than those on the pipeline's body and knowledge (baseline (a)).
    CHECK(ts["baseline"]["fscore"]["2cm_20deg"].get<double>() > fur_summary["baseline"]["fscore"]["2cm_20deg"].get<double>() + 5.0);
    const nf::json& curve = ts["curve"];
    REQUIRE(curve.size() >= 3);
    CHECK(curve.front()["step"] == 0);
    CHECK(curve.front()["seconds"].get<double>() == 0.0);
    CHECK(curve.back()["step"] == 12);
    for (std::size_t i = 0; i < curve.size(); ++i) {
      CHECK(curve[i]["fscore"]["2cm_20deg"].get<double>() >= 0.0);
      CHECK(curve[i]["held_out"]["silhouette_iou"].get<double>() > 0.0);
      CHECK(curve[i]["held_out"]["orientation_error_deg"].get<double>() >= 0.0);  // 64 px: no pixel far enough from the outline
      if (i > 0) CHECK(curve[i]["seconds"].get<double>() >= curve[i - 1]["seconds"].get<double>());
    }
    std::ifstream lines(work / "fur" / "curve.jsonl");
    std::size_t count = 0;
    for (std::string line; std::getline(lines, line);) count += !line.empty();
    CHECK(count == curve.size());
  }
  // Knowledge without any fur: defur still makes M_bald, frames finds no roots and says so.
  const fs::path bald_knowledge = root / "bald_knowledge.json";
  {
    std::ifstream in(work / "knowledge" / "knowledge.json");
    nf::json k = nf::json::parse(in);
    for (auto& [name, region] : k["regions"].items()) region["length_cm"] = 0.0, region["thickness_cm"] = 0.0;
    std::ofstream(bald_knowledge) << k.dump(2);
  }
  const Result hairless = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + body +
                              " --set knowledge.file=" + bald_knowledge.string() + small + " --json");
  INFO(hairless.output);
  REQUIRE(hairless.code == 0);
  CHECK(hairless.output.find("no region of the knowledge grows fur") != std::string::npos);
  const nf::json none = nf::test::json_of(hairless);
  CHECK(none[4]["summary"]["roots"] == 0);
  CHECK(none[5]["summary"]["strands"] == 0);  // the fur stage writes an empty groom and says why
  CHECK(none[6]["summary"]["strands"] == 0);  // and the export writes empty groom files beside the body
  CHECK(hairless.output.find("every region of the knowledge is bald") != std::string::npos);
  CHECK(nf::io::read_hair(work / "fur" / "strands.hair").strand_count() == 0);
  // --scene-scale overrides the scene's unit; annotate prints the table; an edited file feeds back.
  const std::string annotate = "annotate --scene " + scene.string() + " --out " + work.string() + tiny + body;
  const Result scaled = run(annotate + " --set knowledge.preset=cat --scene-scale 50");
  INFO(scaled.output);
  REQUIRE(scaled.code == 0);
  CHECK(scaled.output.find("scale: 50 cm per scene unit (from --scene-scale)") != std::string::npos);
  CHECK(scaled.output.find("inner_earcanal") != std::string::npos);
  const fs::path edited = root / "my_knowledge.json";
  {
    std::ifstream in(work / "knowledge" / "knowledge.json");
    nf::json k = nf::json::parse(in);
    k["regions"]["tail"]["length_cm"] = 7.5;
    std::ofstream(edited) << k.dump(2);
  }
  const Result fed = run(annotate + " --set knowledge.file=" + edited.string() + " --json");
  REQUIRE(fed.code == 0);
  const nf::json fed_json = nf::test::json_of(fed);
  CHECK(fed_json["knowledge"]["regions"]["tail"]["length_cm"].get<double>() == doctest::Approx(7.5));
  CHECK(fed_json["knowledge"]["source"] == "file");
  const Result two = run(annotate + " --set knowledge.preset=cat --set knowledge.file=" + edited.string());
  CHECK(two.code == 2);
  CHECK(two.output.find("give one") != std::string::npos);
  const Result no_model = run(annotate + " --set knowledge.vlm=http://127.0.0.1:9");
  CHECK(no_model.code == 2);
  CHECK(no_model.output.find("knowledge.model") != std::string::npos);

  // A unit that makes the fur 1,000 times longer than the animal is deep: a clear refusal that
  // names the file, the regions and what to do (lengths of 1e-4 units run: see docs/export.md).
  const Result absurd = run("reconstruct --scene " + scene.string() + " --out " + work.string() + tiny + body +
                            " --set knowledge.preset=cat" + small + " --scene-scale 0.003 --to defur");
  CHECK(absurd.code == 1);
  CHECK(absurd.output.find("de-furring would leave nothing of the body") != std::string::npos);
  CHECK(absurd.output.find("Lower thickness_cm in the knowledge") != std::string::npos);
  CHECK(run("reconstruct --scene " + scene.string() + " --out " + (scene / "work").string() + tiny).code == 2);
  CHECK(run("reconstruct --scene " + scene.string() + " --out " + work.string() + " --set nues.steps=3").code == 2);
  const Result bad = run("reconstruct --scene " + scene.string() + " --out " + work.string() + " --set neus.colour=3");
  CHECK(bad.code == 2);
  CHECK(bad.output.find("no setting 'colour'") != std::string::npos);
  CHECK(bad.output.find("colour_weight") != std::string::npos);  // lists the settings

  // A typo fails before any work, and creates nothing.
  const fs::path fresh = root / "fresh";
  const Result typo = run("reconstruct --scene " + scene.string() + " --out " + fresh.string() + " --set neus.stpes=3");
  CHECK(typo.code == 2);
  CHECK(typo.output.find("did you mean 'steps'") != std::string::npos);
  CHECK_FALSE(fs::exists(fresh));
  const Result late = run("reconstruct --scene " + scene.string() + " --out " + fresh.string() + " --set neus.mesh_resolution=2");
  CHECK(late.code == 2);
  CHECK_FALSE(fs::exists(fresh));
  std::ofstream(root / "a_file") << "x";
  const Result file = run("reconstruct --scene " + scene.string() + " --out " + (root / "a_file").string() + " --to neus");
  CHECK(file.code == 1);
  CHECK(file.output.find("is an existing file") != std::string::npos);
  CHECK(file.output.find("internal error") == std::string::npos);

  const Result help = run("reconstruct --help");
  CHECK(help.code == 0);
  CHECK(help.output.find("stages, in order: neus") != std::string::npos);
  const Result stage_help = run("reconstruct --help-stage neus");
  CHECK(stage_help.code == 0);
  CHECK(stage_help.output.find("mesh_resolution") != std::string::npos);
  CHECK(stage_help.output.find("[8, 2048]") != std::string::npos);
  CHECK(run("reconstruct --help-stage nues").code == 2);
  // docs/settings.md's tables are the ones the declarations make (regenerate them with --markdown).
  std::ifstream settings_doc(NF_SETTINGS_DOC);
  const std::string settings_text(std::istreambuf_iterator<char>(settings_doc), {});
  for (const std::string& stage : stage_names()) {
    const Result table = run("reconstruct --help-stage " + stage + " --markdown");
    CHECK_MESSAGE(settings_text.find("### `" + stage + "`\n\n" + table.output) != std::string::npos,
                  "docs/settings.md's " << stage << " settings table is stale: paste `nf_gpu reconstruct --help-stage " << stage
                                        << " --markdown`");
  }
  fs::remove_all(root);
}

TEST_CASE("reconstruct: neus.mesh takes an envelope of the user's own, checked against the masks") {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "nf_cli_envelope";
  fs::remove_all(root);
  const fs::path scene = root / "scene", work = root / "work";
  REQUIRE(run("synth --animal cat --views 8 --res 64 --strands 4000 --spp-axis 1 --out " + scene.string()).code == 0);
  const nf::geometry::Mesh truth = nf::io::read_mesh(scene / "gt" / "outer.ply");
  REQUIRE(truth.normals.size() == truth.positions.size());
  // The user's files: the true envelope; the same turned inside out (winding and normals); in
  // centimetres instead of the scene's metres; shrunk to a fifth about its box centre.
  const fs::path mine = root / "mine.ply", inverted = root / "inverted.ply", in_cm = root / "in_cm.ply", small = root / "small.ply";
  nf::io::write_mesh_ply(mine, truth);
  nf::geometry::Mesh m = truth;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3) std::swap(m.triangles[t + 1], m.triangles[t + 2]);
  for (float& n : m.normals) n = -n;
  nf::io::write_mesh_ply(inverted, m);
  m = truth;
  for (float& x : m.positions) x *= 100.f;
  nf::io::write_mesh_ply(in_cm, m);
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  for (std::size_t i = 0; i < truth.positions.size(); ++i)
    lo[i % 3] = std::min(lo[i % 3], truth.positions[i]), hi[i % 3] = std::max(hi[i % 3], truth.positions[i]);
  m = truth;
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    const float centre = 0.5f * (lo[i % 3] + hi[i % 3]);
    m.positions[i] = centre + 0.2f * (m.positions[i] - centre);
  }
  nf::io::write_mesh_ply(small, m);
  const std::string mine_bytes = slurp(mine);

  const std::string body = " --quality draft --set body.samples=2000 --set body.hypothesis_steps=8 --set body.global_steps=10"
                           " --set body.pose_steps=20 --set body.offset_steps=10 --set body.preview_views=0";
  const auto reconstruct = [&](const fs::path& mesh, const std::string& to) {
    return run("reconstruct --scene " + scene.string() + " --out " + work.string() + body + " --set neus.mesh=" + mesh.string() +
               " --to " + to + " --json");
  };
  const auto stages_of = [](const Result& r) { return nf::test::json_of(r); };
  const Result first = reconstruct(mine, "body");
  INFO(first.output);
  REQUIRE(first.code == 0);
  const nf::json stages = stages_of(first);
  REQUIRE(stages.size() == 2);
  const nf::json& ns = stages[0]["summary"];
  CHECK(ns["source"] == "file");
  CHECK(ns["envelope"]["inside_hull"].get<double>() == doctest::Approx(1.0));
  CHECK_FALSE(ns["envelope"]["flipped"].get<bool>());
  CHECK(ns["ground_truth"]["chamfer_mm"]["mean"].get<double>() < 1e-3);  // M_NeuS is the file's surface
  CHECK(nf::io::read_mesh(work / "neus" / "outer.ply").positions == truth.positions);
  CHECK_FALSE(fs::exists(work / "neus" / "model.nfwt"));  // nothing trained
  // The body stage fits the given envelope like a trained one.
  CHECK(stages[1]["ran"] == true);
  CHECK(stages[1]["summary"]["ground_truth"]["accuracy"].get<double>() > 0.5);

  const Result same = reconstruct(mine, "neus");
  REQUIRE(same.code == 0);
  CHECK(stages_of(same)[0]["ran"] == false);  // the same file: skipped

  // The file's content is the key, not its name: an edited file at the same path reruns.
  const fs::path edited = root / "edited.ply";
  nf::io::write_mesh_ply(edited, truth);
  REQUIRE(reconstruct(edited, "neus").code == 0);
  m = truth;
  for (std::size_t i = 1; i < m.positions.size(); i += 3) m.positions[i] += 0.002f;  // 2 mm up
  nf::io::write_mesh_ply(edited, m);
  const Result moved = reconstruct(edited, "neus");
  REQUIRE(moved.code == 0);
  CHECK(stages_of(moved)[0]["ran"] == true);
  CHECK(nf::io::read_mesh(work / "neus" / "outer.ply").positions == m.positions);

  // An inside-out file is turned back (a warning): the winding outwards again, and the normals
  // follow the winding, whatever the file said.
  const Result turned = reconstruct(inverted, "neus");
  REQUIRE(turned.code == 0);
  CHECK(stages_of(turned)[0]["summary"]["envelope"]["flipped"].get<bool>());
  const nf::geometry::Mesh outer = nf::io::read_mesh(work / "neus" / "outer.ply");
  CHECK(outer.triangles == truth.triangles);
  REQUIRE(outer.normals.size() == truth.normals.size());
  double agree = 0;
  for (std::size_t i = 0; i < outer.normals.size(); ++i) agree += double(outer.normals[i]) * truth.normals[i];
  CHECK(agree / double(truth.vertex_count()) > 0.9);  // mean cosine to the true outward normals

  // Another unit, or part of the animal: refused (exit 1, bad input), naming the file and the
  // measured share; the previous M_NeuS stays.
  const Result cm = reconstruct(in_cm, "neus");
  CHECK(cm.code == 1);
  CHECK(cm.output.find("neus.mesh=" + in_cm.string()) != std::string::npos);
  CHECK(cm.output.find("of its surface lies inside the visual hull of the masks") != std::string::npos);
  const Result part = reconstruct(small, "neus");
  CHECK(part.code == 1);
  CHECK(part.output.find("of the masks' visual hull (50.0 % to 150.0 % needed)") != std::string::npos);
  // No such file, or one inside WORK (whose folders nf_gpu replaces): refused before any stage.
  const Result missing = reconstruct(root / "no_such.ply", "neus");
  CHECK(missing.code == 2);
  CHECK(missing.output.find("neus.mesh=" + (root / "no_such.ply").string() + ": no such file") != std::string::npos);
  const fs::path text = root / "mine.txt";
  fs::copy_file(mine, text);
  const Result unknown = reconstruct(text, "neus");  // io::read_mesh judges the format
  CHECK(unknown.code == 1);
  CHECK(unknown.output.find("unknown mesh format '.txt'") != std::string::npos);
  const Result inside = reconstruct(work / "neus" / "outer.ply", "neus");
  CHECK(inside.code == 2);
  CHECK(inside.output.find("lies inside the WORK folder") != std::string::npos);
  CHECK(nf::io::read_mesh(work / "neus" / "outer.ply").positions == truth.positions);
  CHECK(slurp(mine) == mine_bytes);  // the user's file is never written
  fs::remove_all(root);
}

TEST_CASE("Ctrl-C or SIGTERM during training saves a checkpoint, says how to resume and exits with 130 or 143") {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "nf_cli_sigint";
  fs::remove_all(root);
  const fs::path scene = root / "scene", work = root / "work", log = root / "log.txt";
  REQUIRE(run("synth --animal dog --views 6 --res 48 --strands 2000 --spp-axis 1 --out " + scene.string()).code == 0);
  // Many cheap steps and no periodic checkpoint: only the interrupt can save one.
  const std::string args = "reconstruct --scene " + scene.string() + " --out " + work.string() +
                           " --quality draft --set neus.steps=100000 --set neus.rays=64 --set neus.samples_per_ray=8"
                           " --set neus.fine_samples=4 --set neus.mesh_resolution=32 --set neus.hull_resolution=32"
                           " --set neus.checkpoint_interval=0 --to neus";
  pid_t pid = spawn(args, log);
  REQUIRE(wait_for(log, "training views", 120));
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  kill(pid, SIGINT);
  CHECK(wait_exit(pid) == 130);
  std::string out = slurp(log);
  INFO(out);
  CHECK(out.find("neus: stopped at step ") != std::string::npos);
  CHECK(out.find("checkpoint saved") != std::string::npos);
  CHECK(out.find("resume with the same command: ") != std::string::npos);
  CHECK(fs::exists(work / ".resume" / "neus" / "checkpoint.nfwt"));
  CHECK_FALSE(fs::exists(work / "neus.partial"));
  CHECK_FALSE(fs::exists(work / "neus"));

  // The same command resumes from the saved step.
  {  // the progress line of the stop shows the step reached, not the total
    const std::size_t stop = out.find("s stopped");
    REQUIRE(stop != std::string::npos);
    const std::size_t line = out.rfind('\n', stop);
    CHECK_MESSAGE(out.substr(line, stop - line).find("(100%)") == std::string::npos, out.substr(line, stop - line));
  }
  CHECK(out.find("the scene has only 6 views") != std::string::npos);

  // The same command resumes from the saved step; SIGTERM (a scheduler's, timeout's) stops it the
  // same way, with 128 + 15.
  pid = spawn(args, log);
  CHECK(wait_for(log, "resuming from", 120));
  kill(pid, SIGTERM);
  CHECK(wait_exit(pid) == 143);
  out = slurp(log);
  CHECK(out.find("at step 0") == std::string::npos);
  CHECK(out.find("checkpoint saved") != std::string::npos);
  CHECK(fs::exists(work / ".resume" / "neus" / "checkpoint.nfwt"));
  fs::remove_all(root);
}
