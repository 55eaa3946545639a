#pragma once
// The SPIR-V embedded at build time (cmake/Shaders.cmake), looked up by "module/name[:variant]".
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace nf::gpu {

using ShaderTable = std::vector<std::pair<std::string_view, std::span<const std::uint32_t>>>;

// Adds a table built by nf_compile_shaders with its own TABLE name (the tests' kernels), searched
// after the runtime's own.
void register_shaders(const ShaderTable& table);

// Throws InternalError listing near names when `name` is not embedded.
std::span<const std::uint32_t> find_shader(std::string_view name);
std::vector<std::string> shader_names();

}  // namespace nf::gpu
