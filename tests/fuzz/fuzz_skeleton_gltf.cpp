// libFuzzer target: the rigged glTF's skeleton reader (what edit and pose read of body.glb) on
// arbitrary bytes.
#include "engine/core/error.hpp"
#include "engine/io/mesh.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(data, size, ".glb");
  try {
    (void)nf::io::read_skeleton_gltf(path);
  } catch (const nf::Error&) {
  }
  return 0;
}
