#pragma once
// The fur stage's trained model on disk (fur/model.nfwt): the fur field's MLP parameters, its
// configuration and root box, its per-region length factors, and the strand prior's decoder when
// it was fine-tuned. Loading it
// rebuilds a field that infers the same strands as the one that was saved, which is what lets
// `nf_gpu edit` re-infer a groom without retraining.
#include <cstdint>
#include <filesystem>
#include <memory>

#include "engine/fur/fur_field.hpp"

namespace nf::fur {

void save_fur_model(const std::filesystem::path& path, const FurField& field, const StrandPrior& prior, std::uint64_t steps,
                    bool with_decoder);

struct FurModel {
  std::unique_ptr<StrandPrior> prior;  // the shipped one, or the file's fine-tuned decoder
  std::unique_ptr<FurField> field;
  std::uint64_t steps = 0;
};
// InputError naming the file and the field when it is not a fur model or does not fit the shipped
// prior (latent size, parameter counts).
FurModel load_fur_model(gpu::Context& context, const std::filesystem::path& path);

}  // namespace nf::fur
