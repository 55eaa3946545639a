// libFuzzer target: a stage's record (WORK/<stage>/stage.json) and a checkpoint's key file on
// arbitrary bytes. Neither may throw: an odd record means "run the stage again".
#include "engine/pipeline/stage_record.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(data, size, ".json");
  if (const auto record = nf::pipeline::read_stage_record(path)) {
    (void)record->key.dump();
    if (!record->summary.is_object()) __builtin_trap();
  }
  (void)nf::pipeline::read_json_or_null(path);
  return 0;
}
