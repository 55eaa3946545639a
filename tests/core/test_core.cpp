// engine/core: atomic writes, finite checks, statistics, errors and exit codes.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/content_hash.hpp"
#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/core/stats.hpp"

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
