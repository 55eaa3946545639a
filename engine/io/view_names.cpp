#include "engine/io/view_names.hpp"

#include <cctype>
#include <map>

namespace nf::io {

std::string file_safe_name(const std::string& name) {
  std::string s = name.empty() ? std::string("camera") : name;
  for (char& c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_')) c = '_';
  if (s == "." || s == "..") s = "camera";
  return s;
}

std::vector<std::string> view_file_names(const Scene& scene, const std::vector<std::uint32_t>& views) {
  std::map<std::string, int> uses;
  for (const std::uint32_t v : views) ++uses[file_safe_name(scene.cameras[v].name)];
  std::vector<std::string> names;
  for (const std::uint32_t v : views) {
    std::string name = file_safe_name(scene.cameras[v].name);
    if (uses[name] > 1) name += "_" + std::to_string(v);
    names.push_back(name);
  }
  return names;
}

}  // namespace nf::io
