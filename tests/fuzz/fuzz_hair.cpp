// libFuzzer target: the hair reader on arbitrary bytes.
#include "engine/io/strand_files.hpp"
#include "engine/core/error.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(data, size, ".hair");
  try {
    (void)nf::io::read_hair(path);
  } catch (const nf::Error&) {
  }
  return 0;
}
