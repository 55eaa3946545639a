// libFuzzer target: a SMAL model converted to .npz (--set body.model=), from structured arrays (tests/fuzz/fuzz_input.hpp).
#include "engine/body/smal_model.hpp"
#include "engine/core/error.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(nullptr, 0, ".npz");
  nf::fuzz::FuzzBytes in(data, size);
  nf::fuzz::write_fuzz_npz(path, in, {{"v_template", "<f8"}, {"f", "<u4"}, {"shapedirs", "<f8"}, {"J_regressor", "<f8"}, {"kintree_table", "<i4"}, {"weights", "<f8"}});
  try {
    (void)nf::body::load_smal_model(path);
  } catch (const nf::Error&) {
  }
  return 0;
}
