// libFuzzer target: the groom's colours (fur/colors.npz), from structured arrays (tests/fuzz/fuzz_input.hpp).
#include "engine/core/error.hpp"
#include "engine/fur/strand_colors.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(nullptr, 0, ".npz");
  nf::fuzz::FuzzBytes in(data, size);
  const std::uint64_t strands = in.byte() % 9;  // the groom's strand count the file must match
  nf::fuzz::write_fuzz_npz(path, in, {{"rgb", "<f4"}, {"seen", "<i4"}});
  try {
    const nf::fur::StrandColors c = nf::fur::read_strand_colors(path, strands);
    // What the reader promises the export: a whole table of finite colours.
    if (c.rgb.size() != strands * c.controls * 3 || c.seen.size() != strands) __builtin_trap();
    for (std::uint64_t s = 0; s < strands; ++s) (void)c.at(s, 0.5f);
  } catch (const nf::Error&) {
  }
  return 0;
}
