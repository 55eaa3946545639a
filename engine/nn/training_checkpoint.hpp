#pragma once
// The part of a trainer's checkpoint every trainer shares (the NeuS and fur trainers): what it is,
// the version of its layout, the network and options it was made with (a checkpoint of other ones
// is not resumed), and where training stood. Each trainer adds its own tensors and config entries.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "engine/core/json.hpp"
#include "engine/nn/weights_io.hpp"

namespace nf::nn {

struct CheckpointIdentity {
  std::string kind;  // e.g. "fur checkpoint"
  int version = 0;   // of the trainer's layout
  json field;        // the network's configuration
  json options;      // the training options
};

// Where a trainer stood: its step, training seconds, last report and history (as the trainer
// writes its reports).
struct CheckpointProgress {
  std::uint32_t step = 0;
  double seconds = 0;
  json last;
  json history = json::array();
};

// A file whose config holds the identity and the progress, for the trainer to add to.
WeightsFile checkpoint_file(const CheckpointIdentity& identity, const CheckpointProgress& progress);

// `path` read when it is a checkpoint of this identity; nullopt when it was made with another
// version, network or options (the caller starts afresh). InputError naming the file when it is
// not a `kind` checkpoint or its progress is malformed.
std::optional<WeightsFile> load_checkpoint_of(const std::filesystem::path& path, const CheckpointIdentity& identity);
CheckpointProgress checkpoint_progress(const WeightsFile& file, const std::filesystem::path& path);

// Whether a trainer that has just finished `step` of a run to `until` saves one: every `interval`
// steps (0: never) and at the run's end.
inline bool checkpoint_due(std::uint32_t step, std::uint32_t until, std::uint32_t interval) {
  return interval > 0 && (step % interval == 0 || step == until);
}

}  // namespace nf::nn
