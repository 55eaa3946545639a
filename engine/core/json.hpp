#pragma once
// The project's JSON type (nlohmann/json, from Debian's nlohmann-json3-dev).
#include <nlohmann/json.hpp>

namespace nf {
using json = nlohmann::json;

// JSON text of a value that may hold text from outside (a VLM's answer, a file name): invalid UTF-8
// is replaced by U+FFFD instead of throwing, as nlohmann's dump() does by default.
inline std::string dump_text(const json& value, int indent = -1) {
  return value.dump(indent, ' ', false, json::error_handler_t::replace);
}

// A 3-vector as [x, y, z] (glm vectors, float or double).
template <class V>
json json_vec3(const V& v) {
  return json::array({v.x, v.y, v.z});
}

// A 4x4 matrix (glm, column-major) as four rows, as people read it.
template <class M>
json json_matrix_rows(const M& m) {
  json rows = json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({m[0][r], m[1][r], m[2][r], m[3][r]});
  return rows;
}

}  // namespace nf
