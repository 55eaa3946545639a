#include "engine/body/regions.hpp"

#include "engine/core/error.hpp"

namespace nf::body {

std::optional<Region> region_from_name(std::string_view name) {
  for (int i = 0; i < kRegionCount; ++i)
    if (kRegionNames[i] == name) return static_cast<Region>(i);
  return std::nullopt;
}

std::string region_name(std::int32_t id, const std::string& source) {
  if (id < 0 || id >= kRegionCount)
    throw InputError(source + ": " + std::to_string(id) + " is not a region id (0.." + std::to_string(kRegionCount - 1) + ")");
  return std::string(kRegionNames[id]);
}

}  // namespace nf::body
