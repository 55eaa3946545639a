// libFuzzer target: NeuS's camera file (cameras_sphere.npz, world_mat_<i> per photo) through
// read_scene, from structured arrays (tests/fuzz/fuzz_input.hpp). The folder holds two photos.
#include <filesystem>

#include "engine/core/error.hpp"
#include "engine/io/image.hpp"
#include "engine/io/scene.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path dir = [] {
    const auto d = nf::fuzz::input_folder("scene_neus");
    std::filesystem::create_directories(d / "image");
    nf::io::Image photo{8, 6, 3, std::vector<float>(8 * 6 * 3, 0.5f)};
    for (const char* name : {"000.png", "001.png"}) nf::io::write_png(d / "image" / name, photo);
    return d;
  }();
  nf::fuzz::FuzzBytes in(data, size);
  nf::fuzz::write_fuzz_npz(dir / "cameras_sphere.npz", in, {{"world_mat_0", "<f8"}, {"world_mat_1", "<f8"}});
  try {
    (void)nf::io::read_scene(dir);
  } catch (const nf::Error&) {
  }
  return 0;
}
