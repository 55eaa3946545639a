// libFuzzer target: a fur view kept for a resumed run (engine/fur/fur_view_file), read against a
// scene of one 64 x 48 camera named "000". Garbage is read as no view (nullopt), never a crash.
#include <cstdlib>

#include "engine/fur/fur_view_file.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const nf::io::Scene scene = [] {
    setenv("NF_LOG", "error", 0);  // every rejected input warns (NF_LOG=warn shows why)
    nf::io::Scene s;
    nf::io::Camera c;
    c.name = "000", c.width = 64, c.height = 48, c.fx = c.fy = 60, c.cx = 32, c.cy = 24;
    s.cameras.push_back(c);
    return s;
  }();
  const auto path = nf::fuzz::input_file(data, size, ".nfview");
  if (const auto stored = nf::fur::read_fur_view(path, scene)) {
    const nf::fur::FurView& v = stored->view;
    // What the reader promises the stage: arrays of the crop's size.
    if (v.mask.size() != v.pixels() || v.rgb.size() != 3 * v.pixels() || v.body_depth.size() != v.pixels()) __builtin_trap();
  }
  return 0;
}
