// libFuzzer target: the text camera formats, COLMAP (cameras.txt + images.txt) and Artemis
// (CamPose.inf + Intrinsic.inf), through read_scene as a user's folder would reach them. Byte 0
// picks the format, bytes 1-2 the length of the first file; the rest is the second. The folder
// holds three small photos named as Artemis expects.
#include <filesystem>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/io/image.hpp"
#include "engine/io/scene.hpp"
#include "tests/fuzz/fuzz_input.hpp"

namespace {

std::filesystem::path scene_folder() {
  static const std::filesystem::path dir = [] {
    const auto d = nf::fuzz::input_folder("scene_text");
    nf::io::Image photo{8, 6, 3, std::vector<float>(8 * 6 * 3, 0.5f)};
    for (const char* name : {"img_0000.png", "img_0001.png", "img_0002.png"}) nf::io::write_png(d / name, photo);
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  nf::fuzz::FuzzBytes in(data, size);
  const bool colmap = !(in.byte() & 1);
  const std::size_t first = in.u16();
  const std::string text = in.rest();
  const std::string a = text.substr(0, std::min(first, text.size())), b = text.substr(std::min(first, text.size()));
  const std::filesystem::path dir = scene_folder();
  for (const char* name : {"cameras.txt", "images.txt", "CamPose.inf", "Intrinsic.inf"}) std::filesystem::remove(dir / name);
  std::ofstream(dir / (colmap ? "cameras.txt" : "CamPose.inf"), std::ios::binary) << a;
  std::ofstream(dir / (colmap ? "images.txt" : "Intrinsic.inf"), std::ios::binary) << b;
  try {
    (void)nf::io::read_scene(dir);
  } catch (const nf::Error&) {
  }
  return 0;
}
