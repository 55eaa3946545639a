#include "engine/knowledge/answer_parsing.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "engine/io/json_fields.hpp"

namespace nf::knowledge {
using body::Region;
namespace {

// Answers nest no deeper than this (a dict of lists or of per-region dicts); deeper ones are refused
// before anything copies or prints them.
constexpr int kMaxAnswerDepth = 16;

// A value from an answer, quoted in an error message: short, printable, whole UTF-8 characters.
std::string quoted(const json& value) {
  if (value.is_object()) return "'{...}'";
  if (value.is_array()) {
    bool flat = value.size() <= 8;
    for (const json& v : value) flat = flat && v.is_primitive();
    if (!flat) return "'[...]'";
  }
  return "'" + shorten(value.is_string() ? value.get<std::string>() : value.dump(), 40) + "'";
}

bool is_ident_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool is_ident(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// A Python literal (dict, list, tuple, str, number, True/False/None) rewritten as JSON text. Bare
// words become strings, so NaN or `2.5cm` reach the value checks and are named there.
std::string python_to_json(std::string_view s) {
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    const char c = s[i];
    if (c == '"' || c == '\'') {
      std::string value;
      std::size_t j = i + 1;
      for (; j < s.size() && s[j] != c; ++j) {
        if (s[j] == '\\' && j + 1 < s.size()) {
          const char e = s[++j];
          value += e == 'n' ? '\n' : e == 't' ? '\t' : e;
        } else {
          value += s[j];
        }
      }
      out += dump_text(json(value));
      i = j + 1;
    } else if (c == '#') {
      while (i < s.size() && s[i] != '\n') ++i;
    } else if (std::isdigit(static_cast<unsigned char>(c)) ||
               ((c == '-' || c == '+' || c == '.') && i + 1 < s.size() && (std::isdigit(static_cast<unsigned char>(s[i + 1])) || s[i + 1] == '.'))) {
      std::size_t j = i + 1;
      while (j < s.size() && (std::isdigit(static_cast<unsigned char>(s[j])) || s[j] == '.' ||
                              ((s[j] == 'e' || s[j] == 'E') && j + 1 < s.size() &&
                               (std::isdigit(static_cast<unsigned char>(s[j + 1])) || s[j + 1] == '-' || s[j + 1] == '+')) ||
                              ((s[j] == '-' || s[j] == '+') && (s[j - 1] == 'e' || s[j - 1] == 'E'))))
        ++j;
      std::size_t k = j;
      while (k < s.size() && s[k] == ' ' && k + 1 < s.size() && is_ident_start(s[k + 1])) ++k;
      if (k < s.size() && is_ident_start(s[k])) {  // a number with a unit: keep it as text
        while (k < s.size() && is_ident(s[k])) ++k;
        out += dump_text(json(std::string(s.substr(i, k - i))));
        i = k;
      } else {
        std::string number(s.substr(i, j - i));
        if (number[0] == '+') number.erase(0, 1);
        if (number[0] == '.') number.insert(0, "0");
        if (number.size() > 1 && number[0] == '-' && number[1] == '.') number.insert(1, "0");
        out += number;
        i = j;
      }
    } else if (is_ident_start(c)) {
      std::size_t j = i;
      while (j < s.size() && is_ident(s[j])) ++j;
      const std::string word(s.substr(i, j - i));
      out += word == "True" || word == "true"     ? "true"
             : word == "False" || word == "false" ? "false"
             : word == "None" || word == "null"   ? "null"
                                                  : dump_text(json(word));
      i = j;
    } else if (c == '(') {
      out += '[', ++i;
    } else if (c == ')') {
      out += ']', ++i;
    } else if (c == ',') {
      std::size_t j = i + 1;
      while (j < s.size() && std::isspace(static_cast<unsigned char>(s[j]))) ++j;
      if (j >= s.size() || s[j] == '}' || s[j] == ']' || s[j] == ')') {
        i = j;  // a trailing comma
      } else {
        out += c, ++i;
      }
    } else {
      out += c, ++i;
    }
  }
  return out;
}

std::optional<json> parse_object(std::string_view text) {
  for (int pass = 0; pass < 2; ++pass) {
    std::optional<json> j = io::parse_json_bounded(pass == 0 ? std::string(text) : python_to_json(text), kMaxAnswerDepth);
    if (j && j->is_object()) return j;
  }
  return std::nullopt;
}

// Every balanced {...} of the text as (open, close) positions, in one pass: quotes count only
// inside braces, and an apostrophe after a letter ("cat's") is no quote.
std::vector<std::pair<std::size_t, std::size_t>> brace_pairs(const std::string& text) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  std::vector<std::size_t> open;
  char quote = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quote) {
      if (c == '\\') ++i;
      else if (c == quote) quote = 0;
      continue;
    }
    if (c == '{') open.push_back(i);
    else if (c == '}' && !open.empty()) pairs.emplace_back(open.back(), i), open.pop_back();
    else if (!open.empty() && (c == '"' || (c == '\'' && (i == 0 || !std::isalpha(static_cast<unsigned char>(text[i - 1])))))) quote = c;
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

std::string normalised(const std::string& name) {
  std::string out;
  for (char c : to_lower(name)) {
    if (std::isalnum(static_cast<unsigned char>(c))) out += c;
    else if (!out.empty() && out.back() != '_') out += '_';
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  // Words that describe the value, not the place.
  std::string kept;
  std::size_t start = 0;
  while (start <= out.size()) {
    const std::size_t end = std::min(out.find('_', start), out.size());
    const std::string word = out.substr(start, end - start);
    static const char* kNoise[] = {"fur", "hair", "length", "lengths", "cm", "mm", "thickness", "thick", "effective",
                                   "direction", "directions", "vector", "growth", "growing", "estimate", "estimated",
                                   "value", "region", "area", "part", "the", "of", "coat"};
    if (!word.empty() && std::find_if(std::begin(kNoise), std::end(kNoise), [&](const char* n) { return word == n; }) == std::end(kNoise))
      kept += (kept.empty() ? "" : "_") + word;
    start = end + 1;
  }
  return kept;
}

const std::map<std::string, Region>& region_aliases() {
  static const std::map<std::string, Region> aliases = [] {
    std::map<std::string, Region> a;
    for (int r = 0; r < body::kRegionCount; ++r) a[std::string(body::kRegionNames[std::size_t(r)])] = Region(r);
    const std::pair<const char*, Region> extra[] = {
        {"front_legs", Region::leg_front}, {"front_leg", Region::leg_front}, {"forelegs", Region::leg_front},
        {"foreleg", Region::leg_front}, {"legs_front", Region::leg_front}, {"fore_legs", Region::leg_front},
        {"rear_legs", Region::leg_rear}, {"rear_leg", Region::leg_rear}, {"hind_legs", Region::leg_rear},
        {"hind_leg", Region::leg_rear}, {"hindlegs", Region::leg_rear}, {"back_legs", Region::leg_rear},
        {"back_leg", Region::leg_rear}, {"legs_rear", Region::leg_rear}, {"leg_hind", Region::leg_rear},
        {"paw_pad", Region::paw_pads}, {"pads", Region::paw_pads}, {"pawpads", Region::paw_pads},
        {"paw", Region::paws}, {"feet", Region::paws}, {"rear_paws", Region::paws}, {"hind_paws", Region::paws},
        {"back_paws", Region::paws}, {"rear_feet", Region::paws}, {"hind_feet", Region::paws},
        {"front_paw", Region::front_paws}, {"front_feet", Region::front_paws}, {"fore_paws", Region::front_paws},
        {"forepaws", Region::front_paws}, {"stomach", Region::belly}, {"abdomen", Region::belly},
        {"underbelly", Region::belly}, {"chest", Region::belly}, {"throat", Region::neck},
        {"head", Region::face}, {"muzzle", Region::face}, {"ear", Region::ears}, {"outer_ears", Region::ears},
        {"outer_ear", Region::ears}, {"ears_outer", Region::ears}, {"inner_ear", Region::inner_earcanal},
        {"inner_ears", Region::inner_earcanal}, {"ear_canal", Region::inner_earcanal},
        {"inner_ear_canal", Region::inner_earcanal}, {"earcanal", Region::inner_earcanal},
        {"ear_canals", Region::inner_earcanal}, {"undertail", Region::under_tail},
        {"tail_underside", Region::under_tail}, {"underside_tail", Region::under_tail},
        {"under_the_tail", Region::under_tail}, {"eye", Region::eyes}, {"nose", Region::nosetip},
        {"nose_tip", Region::nosetip}, {"tip_nose", Region::nosetip}, {"torso", Region::body},
        {"back", Region::body}, {"trunk", Region::body}, {"main_body", Region::body}, {"body_back", Region::body},
        {"ruff", Region::mane}, {"neck_ruff", Region::mane}};
    for (const auto& [name, region] : extra) a[name] = region;
    return a;
  }();
  return aliases;
}

double parse_number_prefix(const std::string& s, std::size_t& pos) {
  const char* begin = s.c_str() + pos;
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  if (end == begin) return std::nan("");
  pos += std::size_t(end - begin);
  return v;
}

void skip_spaces(const std::string& s, std::size_t& pos) {
  while (pos < s.size() && std::isspace(static_cast<unsigned char>(s[pos]))) ++pos;
}

// "2", "2.5 cm", "25mm", "2-3 cm", "2 to 3 cm", "~1.5cm", "about 2 cm": cm, or nullopt.
std::optional<double> length_text_cm(std::string s) {
  s = to_lower(s);
  for (const char* prefix : {"approximately", "approx.", "approx", "about", "around", "roughly", "~", "≈", "<", ">"}) {
    const std::size_t at = s.find_first_not_of(' ');
    if (at != std::string::npos && s.compare(at, std::strlen(prefix), prefix) == 0) s.erase(0, at + std::strlen(prefix));
  }
  std::size_t pos = 0;
  skip_spaces(s, pos);
  if (pos < s.size() && (std::isalpha(static_cast<unsigned char>(s[pos])))) return std::nullopt;  // "nan", "inf", words
  double v = parse_number_prefix(s, pos);
  if (!std::isfinite(v)) return std::nullopt;
  skip_spaces(s, pos);
  const std::size_t before_range = pos;
  if (s.compare(pos, 2, "to") == 0) pos += 2;
  else if (pos < s.size() && s[pos] == '-') ++pos;
  else if (s.compare(pos, 3, "\xe2\x80\x93") == 0) pos += 3;  // en dash
  if (pos != before_range) {
    skip_spaces(s, pos);
    std::size_t p = pos;
    const double hi = parse_number_prefix(s, p);
    if (!std::isfinite(hi)) return std::nullopt;
    v = 0.5 * (v + hi), pos = p;
    skip_spaces(s, pos);
  }
  std::string unit = s.substr(pos);
  while (!unit.empty() && (std::isspace(static_cast<unsigned char>(unit.back())) || unit.back() == '.' || unit.back() == ',')) unit.pop_back();
  if (unit.empty() || unit == "cm" || unit.rfind("centimet", 0) == 0) return v;
  if (unit == "mm" || unit.rfind("millimet", 0) == 0) return v / 10.0;
  if (unit == "m" || unit.rfind("met", 0) == 0) return v * 100.0;
  if (unit == "in" || unit == "\"" || unit.rfind("inch", 0) == 0) return v * 2.54;
  if (unit == "um" || unit == "\xc2\xb5m" || unit == "\xce\xbcm" || unit.rfind("micro", 0) == 0 || unit.rfind("micron", 0) == 0) return v / 1e4;
  return std::nullopt;
}

std::optional<glm::vec3> axis_words(const std::string& text) {
  static const std::pair<const char*, glm::vec3> kWords[] = {
      {"+x", {1, 0, 0}},  {"-x", {-1, 0, 0}},  {"x", {1, 0, 0}},         {"+y", {0, 1, 0}},
      {"-y", {0, -1, 0}}, {"y", {0, 1, 0}},    {"+z", {0, 0, 1}},        {"-z", {0, 0, -1}},
      {"z", {0, 0, 1}},   {"up", {0, 1, 0}},   {"upward", {0, 1, 0}},    {"upwards", {0, 1, 0}},
      {"down", {0, -1, 0}}, {"downward", {0, -1, 0}}, {"downwards", {0, -1, 0}}, {"forward", {0, 0, 1}},
      {"forwards", {0, 0, 1}}, {"front", {0, 0, 1}}, {"backward", {0, 0, -1}}, {"backwards", {0, 0, -1}},
      {"back", {0, 0, -1}}, {"left", {1, 0, 0}}, {"right", {-1, 0, 0}}};
  glm::vec3 sum(0.f);
  int found = 0;
  std::string word;
  const std::string t = to_lower(text) + " ";
  for (char c : t) {
    if (std::isalnum(static_cast<unsigned char>(c)) || ((c == '-' || c == '+') && word.empty())) {
      word += c;
      continue;
    }
    if (!word.empty() && word != "and" && word != "slightly" && word != "and/or") {
      const auto* it = std::find_if(std::begin(kWords), std::end(kWords), [&](const auto& w) { return word == w.first; });
      if (it == std::end(kWords)) return std::nullopt;
      sum += it->second, ++found;
    }
    word.clear();
  }
  if (!found) return std::nullopt;
  return sum;
}

double number_of(const json& v, const std::string& where) {
  if (v.is_number()) return v.get<double>();
  if (v.is_string()) {
    std::size_t pos = 0;
    const std::string s = v.get<std::string>();
    skip_spaces(s, pos);
    if (pos < s.size() && std::isalpha(static_cast<unsigned char>(s[pos]))) throw InputError(where + ": " + quoted(v) + " is not a number");
    const double d = parse_number_prefix(s, pos);
    skip_spaces(s, pos);
    if (pos == s.size() && std::isfinite(d)) return d;
  }
  throw InputError(where + ": " + quoted(v) + " is not a number");
}

bool key_has_any(const std::string& key, const std::vector<std::string>& hints) {
  const std::string k = to_lower(key);
  return std::any_of(hints.begin(), hints.end(), [&](const std::string& h) { return k.find(h) != std::string::npos; });
}

std::size_t region_keys(const json& object) {
  std::size_t n = 0;
  for (const auto& [key, value] : object.items()) n += match_region(key).has_value() ? 1 : 0;
  return n;
}

// The objects that hold the per-region entries, the main one first: `object` itself when its keys
// name regions, unless an entry named like the wanted field ({"lengths": {...}}) names more (then
// that one, with the top level's region keys as a supplement: {"lengths": {...}, "mane": {...}});
// else that entry or the only object-valued one not named for another field, one level down.
std::vector<const json*> region_tables(const json& object, const std::vector<std::string>& hints,
                                       const std::vector<std::string>& exclude, const std::string& where) {
  if (!object.is_object()) throw InputError(where + ": expected an object of regions, got " + quoted(object));
  const json* current = &object;
  for (int depth = 0; depth < 3; ++depth) {
    const json* hinted = nullptr;
    const json* only = nullptr;
    int objects = 0;
    for (const auto& [key, value] : current->items()) {
      if (!value.is_object() || key_has_any(key, exclude)) continue;  // {"thickness": {...}} is not a table of lengths
      ++objects, only = &value;
      if (key_has_any(key, hints) && !match_region(key)) hinted = &value;
    }
    const std::size_t here = region_keys(*current);
    if (hinted && region_keys(*hinted) > here) return here ? std::vector<const json*>{hinted, current} : std::vector<const json*>{hinted};
    if (here) return {current};
    const json* next = hinted ? hinted : objects == 1 ? only : nullptr;
    if (!next) break;
    current = next;
  }
  throw InputError(where + ": the answer names no body region (expected keys such as 'body', 'tail', 'ears')");
}

// A value that says "not given": null, "N/A", "none", "unknown", "-".
bool absent(const json& v) {
  if (v.is_null()) return true;
  if (!v.is_string()) return false;
  const std::string s = to_lower(v.get<std::string>());
  return s.empty() || s == "n/a" || s == "na" || s == "none" || s == "unknown" || s == "-" || s == "not visible";
}

template <class T, class Convert>
RegionValues<T> per_region(const json& object, const std::vector<std::string>& hints, const std::vector<std::string>& exclude,
                           const std::string& field, const std::string& where, Convert convert) {
  RegionValues<T> out;
  const std::vector<const json*> tables = region_tables(object, hints, exclude, where);
  for (std::size_t t = 0; t < tables.size(); ++t)
    for (const auto& [key, value] : tables[t]->items()) {
      // "mane_thickness" in a table of lengths is the other field, not the mane's length.
      if (key_has_any(key, exclude)) continue;
      const std::optional<Region> region = match_region(key);
      if (!region) {
        if (t == 0) out.unknown.push_back(shorten(key, 40));
        continue;
      }
      const bool seen = std::any_of(out.values.begin(), out.values.end(), [&](const auto& e) { return e.first == *region; });
      if (t > 0 && seen) continue;  // the main table wins
      const std::string name(body::kRegionNames[std::size_t(*region)]);
      const std::string at = where + ": regions." + name + "." + field + (normalised(key) == name ? "" : " (the answer's '" + shorten(key, 40) + "')");
      const json* v = &value;
      if (value.is_object() && !(value.contains("x") && value.contains("y") && value.contains("z"))) {
        v = nullptr;
        for (const auto& [k, inner] : value.items())
          if (key_has_any(k, hints) && !key_has_any(k, exclude)) v = &inner;
        if (!v) throw InputError(at + ": the entry " + quoted(value) + " has no field like '" + hints.front() + "'");
      }
      if (absent(*v)) continue;  // not given: the fill rules decide
      const T converted = convert(*v, at);
      const auto same = std::find_if(out.values.begin(), out.values.end(), [&](const auto& e) { return e.first == *region; });
      if (same != out.values.end()) same->second = converted;
      else out.values.emplace_back(*region, converted);
    }
  return out;
}

}  // namespace

std::vector<FoundObject> find_objects(const std::string& text) {
  // Bounded work on hostile answers: at most this many candidates parsed, none above 1 MB.
  constexpr int kMaxTries = 200;
  constexpr std::size_t kMaxObject = std::size_t(1) << 20;
  std::vector<FoundObject> found;
  std::size_t label_start = 0, covered_until = 0;
  int tries = 0;
  for (const auto& [open, close] : brace_pairs(text)) {
    if (open < covered_until || close + 1 - open > kMaxObject) continue;  // inside one found, or too big
    if (++tries > kMaxTries) break;
    if (std::optional<json> object = parse_object(std::string_view(text).substr(open, close + 1 - open))) {
      std::string label = to_lower(text.substr(label_start, open - label_start));
      if (label.size() > 200) label = label.substr(label.size() - 200);
      found.push_back({std::move(*object), std::move(label)});
      label_start = covered_until = close + 1;
    }
  }
  return found;
}

std::optional<Region> match_region(const std::string& name) {
  if (name.size() > 40) return std::nullopt;  // no region name is that long; spares the edit distances
  const std::string n = normalised(name);
  if (n.empty()) return std::nullopt;
  // Keys an answer uses for other things, which small misspellings would turn into regions.
  static const char* kMeta[] = {"note", "notes", "comment", "comments", "confidence", "unit", "units", "name",
                                "animal", "species", "explanation", "reasoning", "summary", "total", "average", "remarks"};
  if (std::any_of(std::begin(kMeta), std::end(kMeta), [&](const char* m) { return n == m; })) return std::nullopt;
  const auto& aliases = region_aliases();
  if (const auto it = aliases.find(n); it != aliases.end()) return it->second;
  // Without separators ("legfront", "innerearcanal"), then one misspelt letter (two in long names)
  // of a name of five letters or more.
  const auto compact = [](std::string s) {
    s.erase(std::remove(s.begin(), s.end(), '_'), s.end());
    return s;
  };
  const std::string c = compact(n);
  for (const auto& [alias, region] : aliases)
    if (compact(alias) == c) return region;
  if (c.size() < 5) return std::nullopt;
  const std::size_t allowed = c.size() <= 8 ? 1 : 2;
  std::optional<Region> best;
  std::size_t best_distance = allowed + 1;
  for (const auto& [alias, region] : aliases) {
    const std::string a = compact(alias);
    if (a.size() < 5) continue;
    const std::size_t d = edit_distance(c, a);
    if (d < best_distance) best_distance = d, best = region;
  }
  return best;
}

double length_cm_of(const json& value, const std::string& where) {
  if (value.is_number()) {
    const double v = value.get<double>();
    if (!std::isfinite(v)) throw InputError(where + ": " + quoted(value) + " is not a finite number");
    return v;
  }
  if (value.is_string())
    if (const std::optional<double> cm = length_text_cm(value.get<std::string>())) return *cm;
  throw InputError(where + ": " + quoted(value) + " is not a length (expected a number of cm, e.g. 2.5)");
}

glm::vec3 direction_of(const json& value, const std::string& where, bool allow_zero) {
  glm::dvec3 d(0.0);
  if (value.is_array()) {
    if (value.size() != 3) throw InputError(where + ": " + quoted(value) + " is not 3 numbers [x, y, z]");
    for (int c = 0; c < 3; ++c) d[c] = number_of(value[std::size_t(c)], where + "[" + std::to_string(c) + "]");
  } else if (value.is_object() && value.contains("x") && value.contains("y") && value.contains("z")) {
    d = {number_of(value["x"], where + ".x"), number_of(value["y"], where + ".y"), number_of(value["z"], where + ".z")};
  } else if (value.is_string()) {
    const std::string s = value.get<std::string>();
    const auto open = s.find_first_of("([");
    if (open != std::string::npos) {
      const auto close = s.find_first_of(")]", open);
      const std::optional<json> list = [&]() -> std::optional<json> {
        try {
          return json::parse("[" + s.substr(open + 1, (close == std::string::npos ? s.size() : close) - open - 1) + "]");
        } catch (const json::exception&) {
          return std::nullopt;
        }
      }();
      if (!list) throw InputError(where + ": " + quoted(value) + " is not a direction [x, y, z]");
      return direction_of(*list, where, allow_zero);
    }
    const std::optional<glm::vec3> words = axis_words(s);
    if (!words) throw InputError(where + ": " + quoted(value) + " is not a direction (expected [x, y, z] or words like 'down')");
    d = glm::dvec3(*words);
  } else {
    throw InputError(where + ": " + quoted(value) + " is not a direction [x, y, z]");
  }
  for (int c = 0; c < 3; ++c)
    if (!std::isfinite(d[c]) || std::fabs(d[c]) > 1e6) throw InputError(where + ": " + quoted(value) + " is not finite and of a sane size");
  if (glm::length(d) < 1e-6) {
    if (allow_zero) return glm::vec3(0.0f);
    throw InputError(where + ": " + quoted(value) + " is the zero vector, which has no direction");
  }
  return glm::vec3(glm::normalize(d));
}

RegionValues<double> region_lengths(const json& object, const std::vector<std::string>& hints,
                                    const std::vector<std::string>& exclude, const std::string& field, const std::string& where) {
  return per_region<double>(object, hints, exclude, field, where,
                            [](const json& v, const std::string& at) { return length_cm_of(v, at); });
}

RegionValues<glm::vec3> region_directions(const json& object, const std::string& where) {
  RegionValues<glm::vec3> v = per_region<glm::vec3>(object, {"direction", "dir", "vector", "growth"}, {"length", "thick"}, "direction",
                                                    where, [](const json& d, const std::string& at) { return direction_of(d, at, true); });
  // [0, 0, 0] is how a model says "no direction" (a bald region's): not given, the fill rules decide.
  std::erase_if(v.values, [](const auto& e) { return glm::length(e.second) == 0.0f; });
  return v;
}

namespace {

// The first number (or range) in prose followed by a unit of length, in cm; metres only when asked
// (an animal's length), since "m" in prose about eyes or hairs is rarely a unit. A plain scan: a
// regex would recurse over an answer of megabytes.
std::optional<double> first_length_cm_in_prose(const std::string& text, bool metres = false) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(text[i])) || (i > 0 && (std::isdigit(static_cast<unsigned char>(text[i - 1])) || text[i - 1] == '.')))
      continue;
    std::size_t pos = i;
    if (!std::isfinite(parse_number_prefix(text, pos))) continue;
    std::size_t end = pos;
    skip_spaces(text, end);
    const std::size_t range = end;
    if (text.compare(end, 2, "to") == 0) end += 2;
    else if (end < text.size() && text[end] == '-') ++end;
    else if (text.compare(end, 3, "\xe2\x80\x93") == 0) end += 3;
    if (end != range) {
      skip_spaces(text, end);
      std::size_t second = end;
      if (std::isfinite(parse_number_prefix(text, second)) && second > end) end = second;
      else end = range;
    }
    skip_spaces(text, end);
    std::size_t word_end = end;
    if (text.compare(end, 2, "\xc2\xb5") == 0 || text.compare(end, 2, "\xce\xbc") == 0) word_end += 2;  // micro sign, mu
    while (word_end < text.size() && std::isalpha(static_cast<unsigned char>(text[word_end]))) ++word_end;
    const std::string unit = to_lower(text.substr(end, word_end - end));
    if (unit == "cm" || unit == "mm" || unit == "um" || unit == "\xc2\xb5m" || unit == "\xce\xbcm" || unit.rfind("centimet", 0) == 0 ||
        unit.rfind("millimet", 0) == 0 || unit.rfind("micro", 0) == 0 || unit.rfind("inch", 0) == 0 ||
        (metres && (unit == "m" || unit.rfind("metre", 0) == 0 || unit.rfind("meter", 0) == 0)))
      if (const std::optional<double> cm = length_text_cm(text.substr(i, word_end - i))) return *cm;
  }
  return std::nullopt;
}

}  // namespace

double eye_distance_cm_of(const std::string& text, const std::string& where) {
  for (const FoundObject& o : find_objects(text))
    for (const auto& [key, value] : o.value.items())
      if (key_has_any(key, {"eye", "distance"}) && (value.is_number() || value.is_string()))
        return length_cm_of(value, where + ": " + key);
  if (const std::optional<double> cm = first_length_cm_in_prose(text)) return *cm;
  throw InputError(where + ": the answer gives no distance in cm");
}

double body_length_cm_of(const std::string& text, const std::string& where) {
  const std::vector<FoundObject> objects = find_objects(text);
  // A key naming the body first, then any length; never the tail's. A unit at the key's end
  // ("_m", "_mm", "_in") scales a bare number; else cm, as the question asks.
  for (const std::vector<std::string>& hints : {std::vector<std::string>{"body"}, std::vector<std::string>{"length"}})
    for (const FoundObject& o : objects)
      for (const auto& [key, value] : o.value.items()) {
        if (!key_has_any(key, hints) || key_has_any(key, {"tail"}) || !(value.is_number() || value.is_string())) continue;
        const std::string k = to_lower(key);
        const double unit = k.ends_with("_mm") ? 0.1 : k.ends_with("_m") || k.ends_with("metres") || k.ends_with("meters") ? 100.0
                            : k.ends_with("_in") || k.ends_with("inches") ? 2.54 : 1.0;
        return value.is_number() ? unit * length_cm_of(value, where + ": " + key) : length_cm_of(value, where + ": " + key);
      }
  if (const std::optional<double> cm = first_length_cm_in_prose(text, true)) return *cm;  // a lion's is 1.9 m
  throw InputError(where + ": the answer gives no length in cm");
}

double hair_diameter_mm_of(const std::string& text, const std::string& where) {
  const std::vector<FoundObject> objects = find_objects(text);
  // A key naming the diameter first; one that names a length ("hair_length_cm") never.
  for (const std::vector<std::string>& hints : {std::vector<std::string>{"diam"}, std::vector<std::string>{"hair", "width", "thick"}})
    for (const FoundObject& o : objects)
      for (const auto& [key, value] : o.value.items()) {
        if (!key_has_any(key, hints) || key_has_any(key, {"length", "long"})) continue;
        // A unit in the key ("_um", "_cm"); else mm, as the question asks.
        const std::string k = to_lower(key);
        const double unit = k.ends_with("um") || k.find("micro") != std::string::npos ? 1e-3 : k.ends_with("cm") ? 10.0 : 1.0;
        if (value.is_number()) return unit * number_of(value, where + ": " + key);
        if (!value.is_string()) continue;
        const std::string s = value.get<std::string>();
        std::size_t pos = 0;
        skip_spaces(s, pos);
        const double plain = parse_number_prefix(s, pos);
        skip_spaces(s, pos);
        if (std::isfinite(plain) && pos == s.size()) return unit * plain;
        if (const std::optional<double> cm = length_text_cm(s)) return *cm * 10.0;  // a plain number was read above: this has a unit
        throw InputError(where + ": " + key + " = '" + s + "' is not a diameter (expected a number of mm, e.g. 0.07)");
      }
  if (const std::optional<double> cm = first_length_cm_in_prose(text)) return *cm * 10.0;
  throw InputError(where + ": the answer gives no diameter in mm");
}

}  // namespace nf::knowledge
