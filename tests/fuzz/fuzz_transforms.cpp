// libFuzzer target: the transforms reader on arbitrary bytes.
#include "engine/io/scene.hpp"
#include "engine/core/error.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(data, size, ".json");
  try {
    (void)nf::io::read_transforms_json(path);
  } catch (const nf::Error&) {
  }
  return 0;
}
