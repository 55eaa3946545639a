// engine/core: atomic writes, finite checks, statistics, errors and exit codes, the output guard,
// text helpers and the interrupt flag.
#include <doctest/doctest.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/color.hpp"
#include "engine/core/content_hash.hpp"
#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/core/output_guard.hpp"
#include "engine/core/stats.hpp"
#include "engine/core/text.hpp"

#include <csignal>

using namespace nf;
namespace fs = std::filesystem;

namespace {
std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

TEST_CASE("atomic writes replace the file whole and leave nothing behind when the writer fails") {
  const fs::path dir = fs::temp_directory_path() / "nf_test_atomic";
  fs::remove_all(dir);
  const fs::path file = dir / "sub" / "out.txt";
  write_file_atomic(file, "first");
  CHECK(read(file) == "first");
  write_file_atomic(file, "second version");
  CHECK(read(file) == "second version");
  CHECK_THROWS_AS(write_file_atomic(file,
                                    [](std::ostream& out) {
                                      out << "partial";
                                      throw InputError("writer failed");
                                    }),
                  InputError);
  CHECK(read(file) == "second version");  // the old content survives
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir / "sub")) ++entries;
  CHECK(entries == 1);  // no temporary left
  fs::remove_all(dir);
}

TEST_CASE("require_finite names the input, the element and the value") {
  const std::vector<float> ok = {1.f, -2.f, 0.f};
  CHECK_NOTHROW(require_finite(ok, "weights"));
  const std::vector<float> bad = {1.f, NAN, 0.f};
  CHECK_THROWS_WITH_AS(require_finite(bad, "weights"), doctest::Contains("weights: element 1 is nan"), InputError);
  const std::vector<double> inf = {INFINITY};
  CHECK_THROWS_WITH_AS(require_finite(inf, "scale"), doctest::Contains("scale: element 0 is inf"), InputError);
}

TEST_CASE("median, minimum and maximum") {
  CHECK(median({}) == 0.0);
  CHECK(median({3.0}) == 3.0);
  CHECK(median({5.0, 1.0, 3.0}) == 3.0);
  CHECK(median({4.0, 1.0, 3.0, 2.0}) == 2.5);
  CHECK(minimum({4.0, -1.0}) == -1.0);
  CHECK(maximum({4.0, -1.0}) == 4.0);
}

TEST_CASE("errors carry the exit code of their kind") {
  CHECK(InputError("x").code() == ExitCode::BadInput);
  CHECK(UsageError("x").code() == ExitCode::Usage);
  CHECK(DeviceError("x").code() == ExitCode::DeviceOrInternal);
  CHECK_THROWS_WITH_AS(NF_CHECK(1 + 1 == 3, "arithmetic"), doctest::Contains("arithmetic"), InternalError);
}

TEST_CASE("a failure is classified alike wherever it is caught: exit code, kind, message") {
  const auto failure_of = [](auto thrower) {
    try {
      thrower();
    } catch (const std::exception&) {
      return nf::current_failure();
    }
    return nf::Failure{0, "", ""};
  };
  const nf::Failure input = failure_of([] { throw nf::InputError("scene.json: bad"); });
  CHECK(input.exit_code == 1);
  CHECK(input.line() == "error: scene.json: bad");
  const nf::Failure usage = failure_of([] { throw nf::UsageError("no --out"); });
  CHECK(usage.exit_code == 2);
  const nf::Failure disk = failure_of([] {
    throw std::filesystem::filesystem_error("cannot", "/work/x", std::make_error_code(std::errc::permission_denied));
  });
  CHECK(disk.exit_code == 1);
  CHECK(disk.line().rfind("error: /work/x: ", 0) == 0);
  const nf::Failure bug = failure_of([] { throw std::runtime_error("oops"); });
  CHECK(bug.exit_code == 3);
  CHECK(bug.line() == "internal error: oops");
  nf::set_interrupted(true);
  const nf::Failure stop = failure_of([] { throw nf::Interrupted("fur: stopped"); });
  nf::set_interrupted(false);
  CHECK(stop.exit_code == 130);
  CHECK(stop.line() == "fur: stopped");
}

TEST_CASE("shell words: safe ones as they are, others single-quoted") {
  CHECK(nf::shell_quote("/tmp/a-b_c.d=1,2:3@4%5+6") == "/tmp/a-b_c.d=1,2:3@4%5+6");
  CHECK(nf::shell_quote("my cat") == "'my cat'");
  CHECK(nf::shell_quote("it's") == "'it'\\''s'");
  CHECK(nf::shell_quote("") == "''");
}

TEST_CASE("UTF-8: well-formed text accepted; stray, cut, overlong, surrogate and out-of-range sequences refused") {
  CHECK(nf::is_utf8(""));
  CHECK(nf::is_utf8("plain ascii"));
  CHECK(nf::is_utf8("F(2 cm, 20\xc2\xb0) \xe2\x80\x94 \xf0\x9f\x90\x88"));  // degree sign, em dash, a cat
  CHECK_FALSE(nf::is_utf8("4\xc5\xc5" "0"));          // a lead byte followed by another lead byte
  CHECK_FALSE(nf::is_utf8("\x80"));                    // a stray continuation byte
  CHECK_FALSE(nf::is_utf8("\xe2\x80"));                // cut short at the end
  CHECK_FALSE(nf::is_utf8("\xc0\xaf"));                // '/' in two bytes (overlong)
  CHECK_FALSE(nf::is_utf8("\xe0\x80\xaf"));            // '/' in three bytes (overlong)
  CHECK_FALSE(nf::is_utf8("\xed\xa0\x80"));            // a UTF-16 surrogate
  CHECK_FALSE(nf::is_utf8("\xf4\x90\x80\x80"));        // past U+10FFFF
  CHECK_FALSE(nf::is_utf8("\xff"));
  CHECK(nf::is_utf8("\xf4\x8f\xbf\xbf"));             // U+10FFFF itself
}

TEST_CASE("content hashes: equal bytes hash equal, one changed byte changes the hash, unreadable files are named") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "nf_core_hash";
  fs::create_directories(dir);
  std::ofstream(dir / "a.bin", std::ios::binary) << "whiskers";
  std::ofstream(dir / "b.bin", std::ios::binary) << "whiskers";
  std::ofstream(dir / "c.bin", std::ios::binary) << "whiskerS";
  CHECK(nf::hash_file(dir / "a.bin") == nf::hash_file(dir / "b.bin"));
  CHECK(nf::hash_file(dir / "a.bin") == nf::hash_bytes("whiskers"));
  CHECK(nf::hash_file(dir / "a.bin") != nf::hash_file(dir / "c.bin"));
  CHECK(nf::hash_bytes("").size() == 16);
  CHECK_THROWS_WITH_AS(nf::hash_file(dir / "missing.bin"), doctest::Contains("missing.bin"), nf::InputError);
  fs::remove_all(dir);
}

TEST_CASE("did you mean: edit distance and the closest known name") {
  CHECK(edit_distance("steps", "stpes") == 2);
  CHECK(edit_distance("", "abc") == 3);
  CHECK(edit_distance("kitten", "sitting") == 3);
  CHECK(to_lower("Front Legs \xc3\x89") == "front legs \xc3\x89");  // UTF-8 bytes untouched
  CHECK(shorten("abc", 5) == "abc");
  CHECK(shorten(std::string(39, 'x') + "\xc3\xa9z", 40) == std::string(39, 'x') + "...");  // not inside the character
  CHECK(shorten("a\nb", 5) == "a b");
  const std::vector<std::string> keys{"steps", "rays", "samples_per_ray", "mesh_resolution"};
  CHECK(closest_match("step", keys) == "steps");
  CHECK(closest_match("mesh_reslution", keys) == "mesh_resolution");
  CHECK(closest_match("colour", keys).empty());  // nothing close: no suggestion
  CHECK(did_you_mean("ray", keys) == " (did you mean 'rays'?)");
  CHECK(join({"a", "b", "c"}) == "a, b, c");
}

TEST_CASE("the output guard: never inside an input folder, never over a file nf_gpu did not write") {
  const fs::path root = fs::temp_directory_path() / "nf_test_guard";
  fs::remove_all(root);
  fs::create_directories(root / "scene" / "images");
  std::ofstream(root / "scene" / "images" / "000.png") << "the user's photo";
  CHECK(path_inside(root / "scene" / "images", root / "scene"));
  CHECK(path_inside(root / "out" / ".." / "scene" / "x", root / "scene"));  // through ..
  CHECK_FALSE(path_inside(root / "scene2", root / "scene"));
  fs::create_directory_symlink(root / "scene" / "images", root / "link");
  CHECK(path_inside(root / "link", root / "scene"));  // through a symlink
  CHECK_THROWS_AS(refuse_output_inside(root / "link", root / "scene", "--out", "scene"), UsageError);
  CHECK_NOTHROW(refuse_output_inside(root / "out", root / "scene", "--out", "scene"));

  // A folder holding a file nf_gpu did not write: that file is never claimed.
  OutputFolder theirs(root / "scene" / "images", "render");
  CHECK_THROWS_WITH_AS(theirs.claim("000.png"), doctest::Contains("was not written by nf_gpu"), InputError);
  CHECK(read(root / "scene" / "images" / "000.png") == "the user's photo");

  OutputFolder out(root / "out", "render");
  const fs::path file = out.claim("000.png");
  std::ofstream(file) << "preview";
  CHECK(OutputFolder(root / "out", "render").claim("000.png") == file);  // ours: a later run may replace it
  std::ofstream(root / "out" / "notes.txt") << "mine";
  CHECK_THROWS_AS(OutputFolder(root / "out", "render").claim("notes.txt"), InputError);

  // One result per command and folder: a later render that writes other views removes the earlier
  // render's, never another command's files nor the user's, nor a name outside the folder.
  {
    OutputFolder edit(root / "out", "edit");
    std::ofstream(edit.claim("fur.hair")) << "groom";
  }
  std::ofstream(root / "outside.txt") << "keep";
  std::ofstream(root / "out" / OutputFolder::kRecordName, std::ios::app) << "../outside.txt\trender\n";
  OutputFolder again(root / "out", "render");
  std::ofstream(again.claim("001.png")) << "another view";
  const std::vector<std::string> removed = again.finish();
  CHECK(removed == std::vector<std::string>{"000.png"});
  CHECK_FALSE(fs::exists(root / "out" / "000.png"));
  CHECK(fs::exists(root / "out" / "001.png"));
  CHECK(read(root / "out" / "fur.hair") == "groom");  // the edit's
  CHECK(read(root / "out" / "notes.txt") == "mine");   // the user's
  CHECK(read(root / "outside.txt") == "keep");
  CHECK(OutputFolder(root / "out", "render").claim("000.png") == root / "out" / "000.png");  // no longer recorded, gone: free again

  // Temporaries of a run that was killed (its process gone) go; a live process's stay, and another
  // host's (a shared disk: its pid means nothing here) until it is a day old.
  const fs::path dead = root / "out" / ".fur.usda.tmp999999999-7", live = root / "out" / (".fur.hair.tmp" + std::to_string(getpid() == 1 ? 2 : 1) + "-7");
  const fs::path foreign = root / "out" / ".fur.ply.tmp999999998-7@another-host", stale = root / "out" / ".fur.obj.tmp999999998-7@another-host";
  for (const fs::path& p : {dead, live, foreign, stale}) std::ofstream(p) << "half";
  fs::last_write_time(stale, fs::file_time_type::clock::now() - std::chrono::hours(25));
  std::vector<std::string> gone = remove_stale_temporaries(root / "out");
  std::sort(gone.begin(), gone.end());
  CHECK(gone == std::vector<std::string>{stale.filename().string(), dead.filename().string()});
  CHECK(fs::exists(live));  // pid 1 (or 2) is alive
  CHECK(fs::exists(foreign));

  std::ofstream(root / "a_file") << "x";
  CHECK_THROWS_WITH_AS(OutputFolder(root / "a_file", "render"), doctest::Contains("is an existing file"), InputError);
  CHECK_THROWS_WITH_AS(OutputFolder(root / "a_file" / "sub", "render"), doctest::Contains("is a file, not a folder"), InputError);
  fs::remove_all(root);
}

TEST_CASE("SIGINT sets the interrupt flag instead of ending the process") {
  set_interrupted(false);
  install_interrupt_handler();
  CHECK_FALSE(interrupted());
  std::raise(SIGINT);
  CHECK(interrupted());
  set_interrupted(false);
  CHECK(Interrupted("x").code() == ExitCode::Interrupted);
  CHECK(int(ExitCode::Interrupted) == 130);
}

TEST_CASE("colour: the sRGB curve round-trips, Lab has its reference values, Delta E its unit") {
  for (float v : {0.f, 0.002f, 0.0031308f, 0.04f, 0.2f, 0.5f, 1.f}) CHECK(nf::color::srgb_to_linear(nf::color::linear_to_srgb(v)) == doctest::Approx(v).epsilon(1e-5));
  CHECK(nf::color::srgb_to_linear(0.5f) == doctest::Approx(0.214041f).epsilon(1e-5));  // the standard's mid grey
  CHECK(nf::color::linear_to_srgb(2.f) == doctest::Approx(1.f).epsilon(1e-6));  // clamped
  const glm::vec3 white = nf::color::lab_of_linear(glm::vec3(1.f)), black = nf::color::lab_of_linear(glm::vec3(0.f));
  CHECK(white.x == doctest::Approx(100.f).epsilon(1e-4));
  CHECK(std::abs(white.y) < 1e-2f);
  CHECK(std::abs(white.z) < 1e-2f);
  CHECK(black.x == doctest::Approx(0.f));
  // sRGB red (1, 0, 0): L 53.24, a 80.09, b 67.20 (CIE 1976, D65).
  const glm::vec3 red = nf::color::lab_of_linear({1.f, 0.f, 0.f});
  CHECK(red.x == doctest::Approx(53.24f).epsilon(2e-3));
  CHECK(red.y == doctest::Approx(80.09f).epsilon(2e-3));
  CHECK(red.z == doctest::Approx(67.20f).epsilon(2e-3));
  CHECK(nf::color::delta_e(glm::vec3(1.f), glm::vec3(0.f)) == doctest::Approx(100.f).epsilon(1e-4));
  CHECK(nf::color::delta_e(glm::vec3(0.3f, 0.2f, 0.1f), glm::vec3(0.3f, 0.2f, 0.1f)) == 0.f);
  CHECK(nf::color::luminance(glm::vec3(1.f)) == doctest::Approx(1.f));
}
