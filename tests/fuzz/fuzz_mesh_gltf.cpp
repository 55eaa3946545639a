// libFuzzer target: the glTF reader on arbitrary bytes. The input is named .gltf so that both paths
// are reached: bytes starting with the GLB magic are read as GLB, anything else as glTF JSON.
#include "engine/io/mesh.hpp"
#include "engine/core/error.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(data, size, ".gltf");
  try {
    (void)nf::io::read_mesh_gltf(path);
  } catch (const nf::Error&) {
  }
  return 0;
}
