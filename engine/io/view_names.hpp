#pragma once
// File names for per-view outputs (previews, orientation maps): a camera's name made safe for a
// file name (no separators, no `..`), made unique with the camera index where names collide.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/io/scene.hpp"

namespace nf::io {

std::string file_safe_name(const std::string& name);

// One name per entry of `views` (camera indices), without extension.
std::vector<std::string> view_file_names(const Scene& scene, const std::vector<std::uint32_t>& views);

}  // namespace nf::io
