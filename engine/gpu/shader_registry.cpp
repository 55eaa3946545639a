#include "engine/gpu/shader_registry.hpp"

#include <utility>

#include "engine/core/error.hpp"

namespace nf::gpu {
namespace detail {
const ShaderTable& shader_table();
}
namespace {

std::vector<const ShaderTable*>& tables() {
  static std::vector<const ShaderTable*> all{&detail::shader_table()};
  return all;
}

}  // namespace

void register_shaders(const ShaderTable& table) {
  for (const ShaderTable* t : tables())
    if (t == &table) return;
  tables().push_back(&table);
}

std::span<const std::uint32_t> find_shader(std::string_view name) {
  for (const ShaderTable* table : tables())
    for (const auto& [key, words] : *table)
      if (key == name) return words;
  std::string similar;
  const std::string_view module = name.substr(0, name.find('/'));
  for (const ShaderTable* table : tables())
    for (const auto& entry : *table)
      if (entry.first.substr(0, entry.first.find('/')) == module) similar += " " + std::string(entry.first);
  throw InternalError("no embedded shader named '" + std::string(name) + "'" +
                      (similar.empty() ? std::string() : "; in that module:" + similar));
}

std::vector<std::string> shader_names() {
  std::vector<std::string> names;
  for (const ShaderTable* table : tables())
    for (const auto& entry : *table) names.emplace_back(entry.first);
  return names;
}

}  // namespace nf::gpu
