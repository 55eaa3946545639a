// libFuzzer target: the npz reader on arbitrary bytes.
#include "engine/io/npz.hpp"
#include "engine/core/error.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(data, size, ".npz");
  try {
    for (const auto& name : nf::io::npz_array_names(path)) (void)nf::io::read_npz_array(path, name);
  } catch (const nf::Error&) {
  }
  return 0;
}
