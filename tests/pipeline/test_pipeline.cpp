// The stage framework of `nf_gpu reconstruct` (engine/pipeline/pipeline.hpp) with stand-in stages:
// skipping on unchanged inputs and parameters, reruns on changes and --from, --to, atomic output
// swap (a failed run leaves the previous result whole), resume folders kept across a failure and
// tied to the key, and refusal to touch a folder nf_gpu did not write.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "engine/core/error.hpp"
#include "engine/fur/strand_colors.hpp"
#include "engine/pipeline/export_stage.hpp"
#include "engine/pipeline/fur_stage.hpp"
#include "engine/pipeline/pipeline.hpp"
#include "engine/pipeline/stages.hpp"
#include "tests/support/gpu_test.hpp"

using namespace nf;
namespace fs = std::filesystem;

namespace {

std::string read(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
void write(const fs::path& p, const std::string& s) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << s;
}

// Copies its input file (uppercased) to out/result.txt; remembers how often it ran; can fail midway
// after leaving a checkpoint in its resume folder.
struct CopySettings {
  int repeat = 1;
  std::string mode = "upper";
};

struct CopyStage : pipeline::Stage {
  std::string stage_name;
  std::vector<std::string> deps;
  fs::path input;
  std::string setting = "a";
  pipeline::SettingsSchema<CopySettings> schema{"copy", [](const std::string&) { return CopySettings{}; }};
  CopyStage() {
    schema.add("repeat", [](CopySettings& s) -> auto& { return s.repeat; }, 1, 10, "copies of the text")
        .text("mode", [](CopySettings& s) -> auto& { return s.mode; }, {"upper", "lower"}, "case of the copy");
  }
  int runs = 0;
  bool fail = false;
  bool saw_checkpoint = false;
  std::string name() const override { return stage_name; }
  std::vector<std::string> depends_on() const override { return deps; }
  const pipeline::StageSettings& settings() const override { return schema; }
  std::vector<fs::path> inputs(const pipeline::StageContext&) const override { return {input}; }
  json parameters(const pipeline::StageContext&) const override { return {{"setting", setting}}; }
  json run(pipeline::StageContext&, const fs::path& out, const fs::path& resume) override {
    ++runs;
    saw_checkpoint = fs::exists(resume / "ckpt");
    write(resume / "ckpt", "half way");
    write(out / "partial.txt", "being written");
    if (fail) throw std::runtime_error("killed");
    std::string text = read(input);
    for (char& ch : text) ch = char(std::toupper(static_cast<unsigned char>(ch)));
    write(out / "result.txt", text + setting);
    return {{"length", text.size()}};
  }
};

struct Fixture {
  fs::path root = fs::temp_directory_path() / "nf_pipeline_test";
  fs::path scene = root / "scene", work = root / "work";
  pipeline::StageContext context{test::context(), root / "scene", {}, root / "work", "draft"};
  std::vector<std::unique_ptr<pipeline::Stage>> stages;
  CopyStage* first = nullptr;
  CopyStage* second = nullptr;
  Fixture() {
    fs::remove_all(root);
    write(scene / "photo.txt", "fur");
    auto a = std::make_unique<CopyStage>();
    a->stage_name = "first", a->input = scene / "photo.txt";
    auto b = std::make_unique<CopyStage>();
    b->stage_name = "second", b->input = work / "first" / "result.txt", b->deps = {"first"};
    first = a.get(), second = b.get();
    stages.push_back(std::move(a));
    stages.push_back(std::move(b));
  }
  ~Fixture() { fs::remove_all(root); }
};

}  // namespace

TEST_CASE("stages run once, then are skipped until an input or a parameter changes") {
  Fixture f;
  auto out = pipeline::run_pipeline(f.stages, f.context, {});
  REQUIRE(out.size() == 2);
  CHECK((out[0].ran && out[1].ran));
  CHECK(read(f.work / "second" / "result.txt") == "FURAa");
  CHECK(fs::exists(pipeline::stage_record(f.work, "first")));
  CHECK_FALSE(fs::exists(f.work / "first.partial"));
  CHECK_FALSE(fs::exists(f.work / ".resume" / "first"));  // emptied after success

  out = pipeline::run_pipeline(f.stages, f.context, {});
  CHECK((!out[0].ran && !out[1].ran));
  CHECK(out[0].summary["length"] == 3);  // the record's summary comes back
  CHECK(f.first->runs == 1);

  SUBCASE("a changed scene file reruns the stage and, through its output, the next") {
    write(f.scene / "photo.txt", "whisker");
    out = pipeline::run_pipeline(f.stages, f.context, {});
    CHECK((out[0].ran && out[1].ran));
    CHECK(read(f.work / "second" / "result.txt") == "WHISKERAa");
  }
  SUBCASE("a changed parameter of the second stage reruns only the second") {
    f.second->setting = "b";
    out = pipeline::run_pipeline(f.stages, f.context, {});
    CHECK((!out[0].ran && out[1].ran));
  }
  SUBCASE("--from forces a rerun from that stage; --to stops after one") {
    out = pipeline::run_pipeline(f.stages, f.context, {"second", ""});
    CHECK((!out[0].ran && out[1].ran));
    out = pipeline::run_pipeline(f.stages, f.context, {"first", "first"});
    CHECK(out.size() == 1);
    CHECK(out[0].ran);
    CHECK_THROWS_AS(pipeline::run_pipeline(f.stages, f.context, {"nope", ""}), UsageError);
    CHECK_THROWS_AS(pipeline::run_pipeline(f.stages, f.context, {"", "nope"}), UsageError);
  }
}

TEST_CASE("a failed run leaves the previous output whole and its checkpoint for the next run") {
  Fixture f;
  pipeline::run_pipeline(f.stages, f.context, {});
  write(f.scene / "photo.txt", "mane");
  f.first->fail = true;
  CHECK_THROWS(pipeline::run_pipeline(f.stages, f.context, {}));
  CHECK(read(f.work / "first" / "result.txt") == "FURa");  // the old result, untouched
  CHECK(fs::exists(f.work / ".resume" / "first" / "ckpt"));
  f.first->fail = false;
  pipeline::run_pipeline(f.stages, f.context, {});
  CHECK(f.first->saw_checkpoint);  // resumed from what the failed run left
  CHECK(read(f.work / "first" / "result.txt") == "MANEa");

  SUBCASE("a checkpoint made for other inputs is discarded") {
    f.first->fail = true;
    write(f.scene / "photo.txt", "paw");
    CHECK_THROWS(pipeline::run_pipeline(f.stages, f.context, {}));
    f.first->fail = false;
    write(f.scene / "photo.txt", "tail");
    pipeline::run_pipeline(f.stages, f.context, {});
    CHECK_FALSE(f.first->saw_checkpoint);
  }
}

TEST_CASE("a folder in WORK that nf_gpu did not write is never touched") {
  Fixture f;
  write(f.work / "first" / "my_notes.txt", "mine");
  CHECK_THROWS_WITH_AS(pipeline::run_pipeline(f.stages, f.context, {}), doctest::Contains("holds no stage.json"),
                       InputError);
  CHECK(read(f.work / "first" / "my_notes.txt") == "mine");
}

TEST_CASE("the declared graph: --to runs only what a stage needs, --from reruns its dependents, missing inputs name their stage") {
  Fixture f;
  auto third = std::make_unique<CopyStage>();  // reads the scene only: independent of first and second
  third->stage_name = "third", third->input = f.scene / "photo.txt";
  CopyStage* independent = third.get();
  f.stages.push_back(std::move(third));

  SUBCASE("--from second on an empty WORK runs first before it") {
    const auto out = pipeline::run_pipeline(f.stages, f.context, {"second", ""});
    REQUIRE(out.size() == 3);
    CHECK((out[0].ran && out[1].ran && out[2].ran));
  }
  SUBCASE("--to second leaves the independent stage alone") {
    const auto out = pipeline::run_pipeline(f.stages, f.context, {"", "second"});
    REQUIRE(out.size() == 2);
    CHECK(out[1].name == "second");
    CHECK(independent->runs == 0);
    CHECK_FALSE(fs::exists(f.work / "third"));
  }
  SUBCASE("--from first reruns first and its dependent, not the independent stage") {
    pipeline::run_pipeline(f.stages, f.context, {});
    const auto out = pipeline::run_pipeline(f.stages, f.context, {"first", ""});
    CHECK((out[0].ran && out[1].ran && !out[2].ran));
    CHECK(independent->runs == 1);
  }
  SUBCASE("a rerun of a stage reruns what depends on it even when its output is byte-identical") {
    pipeline::run_pipeline(f.stages, f.context, {});
    f.first->setting = "a";  // same parameters...
    const auto out = pipeline::run_pipeline(f.stages, f.context, {"first", "second"});
    CHECK(f.second->runs == 2);  // ...but first ran, so second ran too
    CHECK(out.size() == 2);
  }
  SUBCASE("--from a stage that --to does not need is a usage error") {
    CHECK_THROWS_WITH_AS(pipeline::run_pipeline(f.stages, f.context, {"third", "second"}),
                         doctest::Contains("does not depend on it"), UsageError);
  }
  SUBCASE("an unknown stage name suggests the closest") {
    CHECK_THROWS_WITH_AS(pipeline::run_pipeline(f.stages, f.context, {"secnd", ""}), doctest::Contains("did you mean 'second'"),
                         UsageError);
  }
  SUBCASE("a deleted output of an unchanged stage is reported as 'rerun stage first'") {
    pipeline::run_pipeline(f.stages, f.context, {});
    fs::remove(f.work / "first" / "result.txt");
    CHECK_THROWS_WITH_AS(pipeline::run_pipeline(f.stages, f.context, {"second", ""}),
                         doctest::Contains("rerun stage first"), InputError);
    CHECK(f.second->runs == 1);
  }
}

TEST_CASE("a failing stage leaves no .partial folder") {
  Fixture f;
  f.first->fail = true;
  CHECK_THROWS(pipeline::run_pipeline(f.stages, f.context, {}));
  CHECK_FALSE(fs::exists(f.work / "first.partial"));
  CHECK(fs::exists(f.work / ".resume" / "first" / "ckpt"));
}

TEST_CASE("settings: one declaration parses, checks and describes every --set") {
  const CopyStage stage;
  const pipeline::StageSettings& s = stage.settings();
  const json defaults = s.values("draft", json::object());
  CHECK(defaults["repeat"] == 1);
  CHECK(defaults["mode"] == "upper");
  CHECK(s.values("draft", {{"repeat", 3}, {"mode", "lower"}})["repeat"] == 3);
  CHECK(s.values("draft", {{"repeat", 3.0}})["repeat"] == 3);  // 3.0 is an integer
  CHECK_THROWS_WITH_AS(s.values("draft", {{"reapet", 3}}), doctest::Contains("did you mean 'repeat'"), UsageError);
  CHECK_THROWS_WITH_AS(s.values("draft", {{"repeat", 2.5}}), doctest::Contains("copy.repeat: expected an integer in [1, 10]"),
                       UsageError);
  CHECK_THROWS_WITH_AS(s.values("draft", {{"repeat", 11}}), doctest::Contains("got 11"), UsageError);
  CHECK_THROWS_WITH_AS(s.values("draft", {{"repeat", "many"}}), doctest::Contains("got \"many\""), UsageError);
  CHECK_THROWS_WITH_AS(s.values("draft", {{"mode", "uper"}}), doctest::Contains("did you mean 'upper'"), UsageError);
  const std::string table = pipeline::describe_settings(s, false);
  CHECK(table.find("repeat") != std::string::npos);
  CHECK(table.find("[1, 10]") != std::string::npos);
  CHECK(table.find("upper, lower") != std::string::npos);
  const std::string markdown = pipeline::describe_settings(s, true);
  CHECK(markdown.find("| `repeat` | integer | [1, 10] | 1 | copies of the text |") != std::string::npos);
}

TEST_CASE("reconstruct checks every option before it touches a file") {
  const fs::path root = fs::temp_directory_path() / "nf_pipeline_options";
  fs::remove_all(root);
  write(root / "scene" / "transforms.json", "{}");
  const auto stages = pipeline::reconstruction_stages();
  pipeline::ReconstructOptions o;
  o.scene = root / "scene", o.work = root / "work", o.quality = "draft";
  o.settings = {"neus.stpes=10"};
  CHECK_THROWS_WITH_AS(pipeline::check_reconstruct_options(stages, o), doctest::Contains("did you mean 'steps'"), UsageError);
  o.settings = {"nues.steps=10"};
  CHECK_THROWS_WITH_AS(pipeline::check_reconstruct_options(stages, o), doctest::Contains("did you mean 'neus'"), UsageError);
  o.settings = {"neus.mesh_resolution=2"};  // found only after training, before
  CHECK_THROWS_WITH_AS(pipeline::check_reconstruct_options(stages, o), doctest::Contains("neus.mesh_resolution"), UsageError);
  o.settings = {"neus.samples_per_ray=8", "neus.fine_samples=8"};  // a combination the stage refuses
  CHECK_THROWS_WITH_AS(pipeline::check_reconstruct_options(stages, o), doctest::Contains("fine_samples"), UsageError);
  o.settings = {"neus.steps=10"};
  CHECK_THROWS_WITH_AS(pipeline::check_reconstruct_options(stages, {o.scene, o.scene / "w", "draft", {}, o.settings}),
                       doctest::Contains("lies inside the scene folder"), UsageError);
  write(root / "a_file", "x");
  CHECK_THROWS_WITH_AS(pipeline::check_reconstruct_options(stages, {o.scene, root / "a_file", "draft", {}, o.settings}),
                       doctest::Contains("is an existing file"), InputError);
  // A run that needs the knowledge stage must name its source; one that stops before it need not.
  CHECK_THROWS_WITH_AS(pipeline::check_reconstruct_options(stages, o), doctest::Contains("knowledge.preset=NAME"), UsageError);
  o.run.to = "body";
  CHECK_NOTHROW(pipeline::check_reconstruct_options(stages, o));
  o.run.to.clear();
  o.settings.push_back("knowledge.preset=cat");
  CHECK(pipeline::check_reconstruct_options(stages, o)["neus"]["steps"] == "10");  // as typed; the schema reads it
  o.scene_scale = 2.5;  // --scene-scale is the knowledge stage's scale, a number; with the setting as well it is refused
  CHECK(pipeline::check_reconstruct_options(stages, o)["knowledge"]["cm_per_unit"] == 2.5);
  o.settings.push_back("knowledge.cm_per_unit=3");
  CHECK_THROWS_WITH_AS(pipeline::check_reconstruct_options(stages, o), doctest::Contains("--scene-scale and --set knowledge.cm_per_unit"),
                       UsageError);
  o.settings.pop_back(), o.scene_scale = 0;
  o.settings.push_back("knowledge.file=" + (root / "a_file").string());
  CHECK_THROWS_WITH_AS(pipeline::check_reconstruct_options(stages, o), doctest::Contains("give one"), UsageError);
  CHECK(stages.front()->settings().values("draft", {{"steps", "10"}})["steps"] == 10);
  CHECK_THROWS_WITH_AS(stages.front()->settings().values("draft", {{"steps", "10x"}}), doctest::Contains("got \"10x\""),
                       UsageError);
  CHECK_FALSE(fs::exists(o.work));  // nothing was created
  fs::remove_all(root);
}

TEST_CASE("the export reads the fur stage's body colours: none, another body's, one per vertex, not several") {
  const fs::path work = fs::temp_directory_path() / "nf_pipeline_body_colors";
  fs::remove_all(work);
  fs::create_directories(work / "fur");
  CHECK(nf::pipeline::read_body_colors(work, 3).empty());  // a fur stage without colours: the body stays grey
  nf::fur::StrandColors c;
  c.controls = 1;
  c.rgb = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f, 0.8f, 0.9f};
  c.seen = {1, 1, 0};
  const fs::path file = nf::pipeline::fur_outputs(work).body_colors();
  nf::fur::write_strand_colors(file, c);
  CHECK(nf::pipeline::read_body_colors(work, 3) == c.rgb);
  CHECK(nf::pipeline::read_body_colors(work, 4).empty());  // another body (fur.truth=all's): grey, with a warning
  c.controls = 3;
  c.rgb.assign(27, 0.5f);
  nf::fur::write_strand_colors(file, c);
  CHECK_THROWS_WITH_AS(nf::pipeline::read_body_colors(work, 3), doctest::Contains("one colour per vertex"), nf::InputError);
  fs::remove_all(work);
}
