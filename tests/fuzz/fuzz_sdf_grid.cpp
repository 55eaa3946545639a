// libFuzzer target: the bald body's signed distance grid (defur/bald_sdf.npz), from structured arrays (tests/fuzz/fuzz_input.hpp).
#include "engine/defur/sdf_file.hpp"
#include "engine/core/error.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(nullptr, 0, ".npz");
  nf::fuzz::FuzzBytes in(data, size);
  nf::fuzz::write_fuzz_npz(path, in, {{"sdf", "<f4"}, {"origin", "<f8"}, {"spacing", "<f8"}, {"band", "<f8"}});
  try {
    (void)nf::defur::read_sdf_file(path);
  } catch (const nf::Error&) {
  }
  return 0;
}
