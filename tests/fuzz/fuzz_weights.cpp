// libFuzzer target: the weights reader on arbitrary bytes.
#include "engine/nn/weights_io.hpp"
#include "engine/core/error.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(data, size, ".nfw");
  try {
    (void)nf::nn::load_weights(path);
  } catch (const nf::Error&) {
  }
  return 0;
}
