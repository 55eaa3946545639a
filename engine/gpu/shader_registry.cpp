#include "engine/gpu/shader_registry.hpp"

#include <utility>

#include "engine/core/error.hpp"

namespace nf::gpu {
namespace detail {
const std::vector<std::pair<std::string_view, std::span<const std::uint32_t>>>& shader_table();
}

std::span<const std::uint32_t> find_shader(std::string_view name) {
  for (const auto& [key, words] : detail::shader_table())
    if (key == name) return words;
  std::string similar;
  const std::string_view module = name.substr(0, name.find('/'));
  for (const auto& entry : detail::shader_table())
    if (entry.first.substr(0, entry.first.find('/')) == module) similar += " " + std::string(entry.first);
  throw InternalError("no embedded shader named '" + std::string(name) + "'" +
                      (similar.empty() ? std::string() : "; in that module:" + similar));
}

std::vector<std::string> shader_names() {
  std::vector<std::string> names;
  for (const auto& entry : detail::shader_table()) names.emplace_back(entry.first);
  return names;
}

}  // namespace nf::gpu
