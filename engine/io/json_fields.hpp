#pragma once
// Typed reads from parsed JSON whose errors name the file and the field's path, e.g.
//   transforms.json: frames[3].transform_matrix[1][2]: expected a number, got "a"
// so that no reader surfaces nlohmann's exception text ("[json.exception.type_error.302] ...").
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include <glm/glm.hpp>

#include "engine/core/json.hpp"

namespace nf::io {

// Parses `text`; a syntax error becomes InputError "<source>: not valid JSON (line 1, column 9: ...)".
json parse_json(std::string_view text, const std::string& source);
// Untrusted text (a server's answer): nullopt when it is not JSON or nests deeper than `max_depth`
// (copying or printing a deeper value would recurse that deep).
std::optional<json> parse_json_bounded(std::string_view text, int max_depth);
// The whole file, parsed as above; InputError "<file>: cannot open" when it cannot be read.
json read_json_file(const std::filesystem::path& path);

// nlohmann's message without its "[json.exception.parse_error.101] " tag.
std::string json_error_text(const json::exception& e);
// A JSON value for an error message: strings quoted and cut at 40 characters, numbers and literals
// as written, "an object" / "an array" for containers.
std::string describe_json(const json& value);

// A value and where it lies in its file. Children are reached through the checked accessors
// below, each extending the path ("frames" -> "frames[3]" -> "frames[3].file_path").
class JsonField {
 public:
  JsonField(const json& value, std::string source, std::string path = {})
      : value_(&value), source_(std::move(source)), path_(std::move(path)) {}

  const json& value() const { return *value_; }
  const std::string& path() const { return path_; }

  bool has(std::string_view key) const { return value_->is_object() && value_->contains(key); }
  std::optional<JsonField> find(std::string_view key) const;  // absent: nullopt; not an object: throws
  JsonField at(std::string_view key) const;                   // "<path>.key is missing"
  JsonField at(std::size_t index) const;                      // "<path>[i] is missing (the array has n entries)"
  std::size_t size() const;                                   // of an array

  double number() const;  // any JSON number (finite checks are the caller's)
  std::string string() const;

  // InputError "<source>: <path>: <what>".
  [[noreturn]] void fail(const std::string& what) const;

 private:
  const json& array() const;
  const json& object() const;
  std::string child(std::string_view key) const;

  const json* value_;
  std::string source_, path_;
};

// A 4x4 matrix written as four rows (core/json.hpp's json_matrix_rows), errors naming the entry.
glm::dmat4 matrix_rows(const JsonField& rows);

}  // namespace nf::io
