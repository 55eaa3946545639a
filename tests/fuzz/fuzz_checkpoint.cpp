// libFuzzer target: the checkpoints of the neus and fur stages (WORK/.resume/<stage>/), which are
// weights files whose configuration carries the training state. The first byte picks the reader and
// its variant (NeuS with or without a hash table, fur with or without the decoder); the rest is the
// file.
#include "engine/core/error.hpp"
#include "engine/fur/fur_trainer.hpp"
#include "engine/neus/neus_trainer.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const auto path = nf::fuzz::input_file(data + 1, size - 1, ".nfwt");
  try {
    const nf::nn::WeightsFile file = nf::nn::load_weights(path);
    const bool variant = data[0] & 2;
    if (data[0] & 1) (void)nf::fur::parse_fur_checkpoint(file, path, variant);
    else (void)nf::neus::parse_neus_checkpoint(file, path, variant);
  } catch (const nf::Error&) {
  }
  return 0;
}
