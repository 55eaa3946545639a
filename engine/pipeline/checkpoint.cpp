#include "engine/pipeline/checkpoint.hpp"

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"

namespace nf::pipeline {

bool resume_or_discard(const std::string& stage, const std::filesystem::path& checkpoint,
                       const std::function<bool()>& load, const std::function<void()>& reset) {
  if (!std::filesystem::exists(checkpoint)) return false;
  std::string why = "it was made with other settings";
  bool resumed = false;
  try {
    resumed = load();
  } catch (const InputError& e) {
    why = e.what();
  }
  if (resumed) return true;
  log::warn(stage, ": discarding the checkpoint ", checkpoint.string(), " (", why, "); starting afresh");
  reset();
  std::filesystem::remove(checkpoint);
  return false;
}

}  // namespace nf::pipeline
