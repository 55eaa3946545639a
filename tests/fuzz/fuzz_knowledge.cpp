// libFuzzer target: the knowledge.json reader on arbitrary bytes.
#include "engine/core/error.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(data, size, ".json");
  try {
    (void)nf::knowledge::read_knowledge(path);
  } catch (const nf::Error&) {
  }
  return 0;
}
