// libFuzzer target: the roots file (frames/roots.npz, fur/roots.npz), from structured arrays (tests/fuzz/fuzz_input.hpp).
#include "engine/fur/roots.hpp"
#include "engine/core/error.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(nullptr, 0, ".npz");
  nf::fuzz::FuzzBytes in(data, size);
  nf::fuzz::write_fuzz_npz(path, in, {{"face", "<u4"}, {"barycentric", "<f4"}, {"position", "<f4"}, {"tangent", "<f4"}, {"bitangent", "<f4"}, {"normal", "<f4"}, {"direction", "<f4"}, {"region", "<i4"}, {"length", "<f4"}});
  try {
    (void)nf::fur::read_roots(path);
  } catch (const nf::Error&) {
  }
  return 0;
}
