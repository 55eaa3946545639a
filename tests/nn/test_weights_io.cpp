// The weights format: round trips, and malformed files rejected with the file and field named.
#include <doctest/doctest.h>

#include <filesystem>
#include <cstring>
#include <fstream>

#include "engine/core/error.hpp"
#include "tests/support/files.hpp"
#include "engine/nn/init.hpp"
#include "engine/nn/weights_io.hpp"

using namespace nf;
using namespace nf::nn;
namespace fs = std::filesystem;
using nf::test::slurp;
using nf::test::spit;

namespace {

MlpConfig net() {
  MlpConfig c;
  c.input_dim = 63;
  c.hidden = {64, 128};
  c.output_dim = 5;
  return c;
}

}  // namespace

TEST_CASE("MLP weights survive a round trip exactly") {
  const fs::path path = fs::temp_directory_path() / "nf_test_weights.nfw";
  const MlpConfig c = net();
  const auto params = initial_parameters(c, {InitScheme::KaimingUniform, 9});
  save_weights(path, mlp_weights(c, params));
  const WeightsFile loaded = load_weights(path);
  CHECK(mlp_parameters(c, loaded, path) == params);
  CHECK(loaded.tensor("layer1.weight", path).shape == std::vector<std::uint64_t>{128, 64});
  fs::remove(path);
}

TEST_CASE("an empty tensor list and a single tensor round-trip") {
  const fs::path path = fs::temp_directory_path() / "nf_test_weights_small.nfw";
  save_weights(path, WeightsFile{json{{"kind", "empty"}}, {}});
  CHECK(load_weights(path).tensors.empty());
  save_weights(path, WeightsFile{json::object(), {{"one", {1}, {3.5f}}}});
  CHECK(load_weights(path).tensor("one", path).values == std::vector<float>{3.5f});
  fs::remove(path);
}

TEST_CASE("malformed weights files name the file and the problem") {
  const fs::path path = fs::temp_directory_path() / "nf_test_weights_bad.nfw";
  const MlpConfig c = net();
  save_weights(path, mlp_weights(c, initial_parameters(c, {})));
  const std::string good = slurp(path);

  spit(path, "GARBAGE!");
  CHECK_THROWS_WITH_AS(load_weights(path), doctest::Contains("magic"), InputError);
  std::string v2 = good;
  v2[4] = 2;
  spit(path, v2);
  CHECK_THROWS_WITH_AS(load_weights(path), doctest::Contains("version 2"), InputError);
  spit(path, good.substr(0, good.size() - 100));
  CHECK_THROWS_WITH_AS(load_weights(path), doctest::Contains("truncated"), InputError);
  spit(path, good.substr(0, 20));
  CHECK_THROWS_WITH_AS(load_weights(path), doctest::Contains("header length"), InputError);
  std::string nan = good;
  const std::uint32_t bits = 0x7fc00000u;
  std::memcpy(&nan[nan.size() - 4], &bits, 4);
  spit(path, nan);
  CHECK_THROWS_WITH_AS(load_weights(path), doctest::Contains("not finite"), InputError);

  // A file for another network: the mismatch is named.
  save_weights(path, mlp_weights(c, initial_parameters(c, {})));
  MlpConfig other = c;
  other.hidden[1] = 256;
  CHECK_THROWS_WITH_AS(mlp_parameters(other, load_weights(path), path), doctest::Contains("does not match"), InputError);
  // Right configuration, wrong tensor shape.
  WeightsFile w = mlp_weights(c, initial_parameters(c, {}));
  w.tensors[2].shape = {64, 128};
  save_weights(path, w);
  CHECK_THROWS_WITH_AS(mlp_parameters(c, load_weights(path), path), doctest::Contains("'layer1.weight' has shape [64, 128]"),
                       InputError);
  fs::remove(path);
  CHECK_THROWS_WITH_AS(load_weights(path), doctest::Contains("cannot open"), InputError);
}
