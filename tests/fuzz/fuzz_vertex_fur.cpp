// libFuzzer target: the per-vertex fur of M_bald (defur/vertex_fur.npz) and the per-face frames
// (frames/frames.npz), from structured arrays (tests/fuzz/fuzz_input.hpp); the first two bytes are
// the vertex (face) count the reader expects.
#include "engine/core/error.hpp"
#include "engine/defur/vertex_fur.hpp"
#include "engine/pipeline/fur_stage.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nf::fuzz::input_file(nullptr, 0, ".npz");
  nf::fuzz::FuzzBytes in(data, size);
  const std::size_t count = in.u16();
  nf::fuzz::write_fuzz_npz(path, in, {{"region", "<i4"}, {"length", "<f4"}, {"direction", "<f4"}, {"tangent", "<f4"}, {"normal", "<f4"}});
  try {
    (void)nf::defur::read_vertex_fur(path, count);
  } catch (const nf::Error&) {
  }
  try {
    (void)nf::pipeline::read_face_frames(path, count);
  } catch (const nf::Error&) {
  }
  return 0;
}
