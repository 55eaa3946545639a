#include "engine/io/ground_truth.hpp"

#include <cmath>
#include <fstream>

#include "engine/core/error.hpp"

namespace nf::io {

std::optional<GroundTruth> find_ground_truth(const std::filesystem::path& scene_dir) {
  GroundTruth gt;
  gt.dir = scene_dir / "gt";
  if (!std::filesystem::exists(gt.scene_json())) return std::nullopt;
  std::ifstream in(gt.scene_json());
  gt.info = json::parse(in, nullptr, false);
  if (!gt.info.is_object()) throw InputError(gt.scene_json().string() + ": not a JSON object");
  const json cm = gt.info.value("cm_per_unit", json());
  if (!cm.is_number() || !(cm.get<double>() > 0) || !std::isfinite(cm.get<double>()))
    throw InputError(gt.scene_json().string() + ": cm_per_unit: expected a positive number, got " + cm.dump());
  gt.cm_per_unit = cm.get<double>();
  return gt;
}

}  // namespace nf::io
