#include "engine/nn/training_checkpoint.hpp"

#include "engine/core/error.hpp"

namespace nf::nn {

WeightsFile checkpoint_file(const CheckpointIdentity& identity, const CheckpointProgress& progress) {
  WeightsFile file;
  file.config = {{"kind", identity.kind},    {"version", identity.version}, {"field", identity.field},
                 {"options", identity.options}, {"step", progress.step},      {"seconds", progress.seconds},
                 {"last", progress.last},       {"history", progress.history}};
  return file;
}

std::optional<WeightsFile> load_checkpoint_of(const std::filesystem::path& path, const CheckpointIdentity& identity) {
  WeightsFile file = load_weights(path);
  const json& c = file.config;
  if (!c.is_object() || c.value("kind", json()) != identity.kind) throw InputError(path.string() + ": not a " + identity.kind);
  if (c.value("version", json()) != identity.version || c.value("field", json()) != identity.field ||
      c.value("options", json()) != identity.options)
    return std::nullopt;
  return file;
}

CheckpointProgress checkpoint_progress(const WeightsFile& file, const std::filesystem::path& path) {
  CheckpointProgress p;
  try {
    const json& c = file.config;
    p.step = c.at("step").get<std::uint32_t>();
    p.seconds = c.at("seconds").get<double>();
    p.last = c.at("last");
    p.history = c.at("history");
    if (p.history.is_null()) p.history = json::array();  // as the trainers read it before: no history
    if (!p.history.is_array()) throw InputError(path.string() + ": 'history' is not an array");
  } catch (const json::exception& e) {
    throw InputError(path.string() + ": " + e.what());
  }
  return p;
}

}  // namespace nf::nn
