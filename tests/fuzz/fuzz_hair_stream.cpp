// libFuzzer target: the streamed .hair reader (what the export reads the groom with) on arbitrary
// bytes, in small chunks so the chunking is exercised too.
#include "engine/core/error.hpp"
#include "engine/io/strand_stream.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(data, size, ".hair");
  try {
    const nf::io::StrandStream s = nf::io::stream_hair_file(path, 7);
    std::uint64_t points = 0, total = 0;
    for (std::uint64_t i = 0; i < s.strands; ++i) total += s.points_in(i);
    s.each_chunk([&](std::span<const float> xyz) { points += xyz.size() / 3; });
    if (points != s.points || total != s.points) __builtin_trap();  // the stream must hand over what it announced
  } catch (const nf::Error&) {
  }
  return 0;
}
