#include "engine/io/json_fields.hpp"

#include <cmath>

#include <fstream>
#include <iterator>

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"

namespace nf::io {

std::string json_error_text(const json::exception& e) {
  std::string text = e.what();
  if (text.rfind("[json.exception.", 0) == 0) {
    const std::size_t close = text.find("] ");
    if (close != std::string::npos) text.erase(0, close + 2);
  }
  // "parse error at line 1, column 9: ..." reads better as "line 1, column 9: ...".
  if (text.rfind("parse error at ", 0) == 0) text.erase(0, 15);
  return text;
}

json parse_json(std::string_view text, const std::string& source) {
  try {
    return json::parse(text.begin(), text.end());
  } catch (const json::exception& e) {
    throw InputError(source + ": not valid JSON (" + json_error_text(e) + ")");
  }
}

glm::dmat4 matrix_rows(const JsonField& rows) {
  if (rows.size() != 4) rows.fail("expected 4 rows of 4 numbers, got " + std::to_string(rows.size()) + " rows");
  glm::dmat4 m(1.0);
  for (std::size_t r = 0; r < 4; ++r) {
    const JsonField row = rows.at(r);
    if (row.size() != 4) row.fail("expected 4 numbers, got " + std::to_string(row.size()));
    for (std::size_t c = 0; c < 4; ++c) {
      const double v = row.at(c).number();
      if (!std::isfinite(v)) row.at(c).fail("not a finite number");
      m[int(c)][int(r)] = v;
    }
  }
  return m;
}

std::optional<json> parse_json_bounded(std::string_view text, int max_depth) {
  struct TooDeep {};
  try {
    return json::parse(text, [max_depth](int depth, json::parse_event_t, json&) {
      if (depth > max_depth) throw TooDeep{};
      return true;
    });
  } catch (const json::exception&) {
  } catch (const TooDeep&) {
  }
  return std::nullopt;
}

json read_json_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_json(text, path.string());
}

std::string describe_json(const json& value) {
  if (value.is_string()) {
    const auto& s = value.get_ref<const std::string&>();
    // Cut at a character boundary, and invalid UTF-8 shown as U+FFFD: the text ends up in a message.
    return json(shorten(s, 40)).dump(-1, ' ', false, json::error_handler_t::replace);
  }
  if (value.is_object()) return "an object";
  if (value.is_array()) return "an array";
  return value.dump();  // number, true, false, null
}

void JsonField::fail(const std::string& what) const {
  throw InputError(source_ + ": " + (path_.empty() ? what : path_ + ": " + what));
}

const json& JsonField::object() const {
  if (!value_->is_object()) fail("expected an object, got " + describe_json(*value_));
  return *value_;
}

const json& JsonField::array() const {
  if (!value_->is_array()) fail("expected an array, got " + describe_json(*value_));
  return *value_;
}

std::string JsonField::child(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

std::optional<JsonField> JsonField::find(std::string_view key) const {
  const json& o = object();
  const auto it = o.find(key);
  if (it == o.end()) return std::nullopt;
  return JsonField(*it, source_, child(key));
}

JsonField JsonField::at(std::string_view key) const {
  if (auto field = find(key)) return *field;
  throw InputError(source_ + ": " + child(key) + " is missing");
}

JsonField JsonField::at(std::size_t index) const {
  const json& a = array();
  const std::string name = path_ + "[" + std::to_string(index) + "]";
  if (index >= a.size())
    throw InputError(source_ + ": " + name + " is missing (the array has " + std::to_string(a.size()) + " entries)");
  return JsonField(a[index], source_, name);
}

std::size_t JsonField::size() const { return array().size(); }

double JsonField::number() const {
  if (!value_->is_number()) fail("expected a number, got " + describe_json(*value_));
  return value_->get<double>();
}

std::string JsonField::string() const {
  if (!value_->is_string()) fail("expected a string, got " + describe_json(*value_));
  return value_->get<std::string>();
}

}  // namespace nf::io
