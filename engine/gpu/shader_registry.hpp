#pragma once
// The SPIR-V embedded at build time (cmake/Shaders.cmake), looked up by "module/name[:variant]".
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace nf::gpu {

// Throws InternalError listing near names when `name` is not embedded.
std::span<const std::uint32_t> find_shader(std::string_view name);
std::vector<std::string> shader_names();

}  // namespace nf::gpu
