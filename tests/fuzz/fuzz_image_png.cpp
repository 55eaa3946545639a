// libFuzzer target: read_image on arbitrary bytes named .png.
#include "engine/core/error.hpp"
#include "engine/io/image.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(data, size, ".png");
  try {
    (void)nf::io::read_image(path);
  } catch (const nf::Error&) {
  }
  return 0;
}
