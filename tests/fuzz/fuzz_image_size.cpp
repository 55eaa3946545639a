// libFuzzer target: the image header and completeness checks on arbitrary bytes.
#include "engine/io/image_size.hpp"
#include "engine/core/error.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(data, size, ".png");
  try {
    (void)nf::io::image_size(path);
  } catch (const nf::Error&) {
  }
  try {
    nf::io::require_complete_image(path);
  } catch (const nf::Error&) {
  }
  return 0;
}
