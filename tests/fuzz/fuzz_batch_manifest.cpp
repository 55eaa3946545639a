// libFuzzer target: a batch manifest (nf_gpu batch run) on arbitrary bytes. The first byte picks
// the form (even: JSON, odd: CSV); the manifest lies in a folder holding the scene folders "a" and
// "b", so inputs that name them reach the per-scene checks. Bad input must be an nf::Error.
#include "engine/batch/manifest.hpp"
#include "engine/core/error.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  nf::fuzz::FuzzBytes in(data, size);
  const bool csv = in.byte() & 1;
  const auto dir = nf::fuzz::input_folder("batch_manifest");
  std::filesystem::create_directories(dir / "a");
  std::filesystem::create_directories(dir / "b");
  const auto file = dir / (csv ? "m.csv" : "m.json");
  std::ofstream(file, std::ios::binary) << in.rest();
  try {
    for (const nf::batch::BatchTask& t : nf::batch::read_manifest(file)) {
      if (t.name.empty() || t.scene.empty() || t.work.empty()) __builtin_trap();
      (void)nf::batch::task_from_json(nf::batch::to_json(t));
    }
  } catch (const nf::Error&) {
  }
  return 0;
}
