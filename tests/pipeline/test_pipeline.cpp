// The stage framework of `nf_gpu reconstruct` (engine/pipeline/pipeline.hpp) with stand-in stages:
// skipping on unchanged inputs and parameters, reruns on changes and --from, --to, atomic output
// swap (a failed run leaves the previous result whole), resume folders kept across a failure and
// tied to the key, and refusal to touch a folder nf_gpu did not write.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "engine/core/error.hpp"
#include "engine/pipeline/pipeline.hpp"
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
struct CopyStage : pipeline::Stage {
  std::string stage_name;
  fs::path input;
  std::string setting = "a";
  int runs = 0;
  bool fail = false;
  bool saw_checkpoint = false;
  std::string name() const override { return stage_name; }
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
    b->stage_name = "second", b->input = work / "first" / "result.txt";
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
