// The weights format: round trips, and malformed files rejected with the file and field named; the
// trainers' shared checkpoint skeleton.
#include <doctest/doctest.h>

#include <filesystem>
#include <cstring>
#include <fstream>

#include "engine/core/error.hpp"
#include "tests/support/files.hpp"
#include "engine/nn/init.hpp"
#include "engine/nn/training_checkpoint.hpp"
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

TEST_CASE("a trainer's checkpoint is resumed only by the same kind, version, network and options") {
  const fs::path dir = fs::temp_directory_path() / "nf_training_checkpoint";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const CheckpointIdentity id{"toy checkpoint", 3, {{"width", 8}}, {{"lr", 0.01}}};
  WeightsFile file = checkpoint_file(id, {42, 1.5, {{"loss", 0.25}}, json::array({{{"loss", 1.0}}, {{"loss", 0.5}}})});
  file.config["extra"] = 7;
  file.tensors.push_back({"field", {3}, {1.f, 2.f, 3.f}});
  save_weights(dir / "a.nfwt", file);

  const std::optional<WeightsFile> same = load_checkpoint_of(dir / "a.nfwt", id);
  REQUIRE(same.has_value());
  CHECK(same->config["extra"] == 7);
  CHECK(same->tensor("field", dir / "a.nfwt").values == std::vector<float>{1.f, 2.f, 3.f});
  const CheckpointProgress progress = checkpoint_progress(*same, dir / "a.nfwt");
  CHECK(progress.step == 42);
  CHECK(progress.seconds == 1.5);
  CHECK(progress.last["loss"] == 0.25);
  CHECK(progress.history.size() == 2);

  // Other settings: not resumed (the stage starts afresh); another kind: refused, naming the file.
  CheckpointIdentity other = id;
  other.version = 4;
  CHECK_FALSE(load_checkpoint_of(dir / "a.nfwt", other).has_value());
  other = id, other.field["width"] = 16;
  CHECK_FALSE(load_checkpoint_of(dir / "a.nfwt", other).has_value());
  other = id, other.options["lr"] = 0.02;
  CHECK_FALSE(load_checkpoint_of(dir / "a.nfwt", other).has_value());
  CheckpointIdentity fur = id;
  fur.kind = "fur checkpoint";
  CHECK_THROWS_WITH_AS(load_checkpoint_of(dir / "a.nfwt", fur), doctest::Contains("a.nfwt: not a fur checkpoint"), InputError);

  WeightsFile broken = file;
  broken.config["step"] = "many";
  CHECK_THROWS_WITH_AS(checkpoint_progress(broken, dir / "b.nfwt"), doctest::Contains("b.nfwt"), InputError);
  broken = file;
  broken.config["history"] = 3;
  CHECK_THROWS_WITH_AS(checkpoint_progress(broken, dir / "b.nfwt"), doctest::Contains("'history' is not an array"), InputError);

  // Saved every interval and at the run's end; never with interval 0.
  CHECK(checkpoint_due(100, 300, 100));
  CHECK_FALSE(checkpoint_due(101, 300, 100));
  CHECK(checkpoint_due(57, 57, 100));
  CHECK_FALSE(checkpoint_due(57, 57, 0));
  fs::remove_all(dir);
}
