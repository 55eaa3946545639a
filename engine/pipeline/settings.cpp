#include "engine/pipeline/settings.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "engine/core/text.hpp"

namespace nf::pipeline {

const std::vector<std::string>& quality_names() {
  static const std::vector<std::string> names{"draft", "default", "paper"};
  return names;
}

const char* setting_type_name(SettingType type) {
  switch (type) {
    case SettingType::Integer: return "integer";
    case SettingType::Real: return "number";
    case SettingType::Flag: return "flag";
    case SettingType::Text: return "text";
  }
  return "?";
}

std::vector<std::string> StageSettings::keys() const {
  std::vector<std::string> out;
  for (const SettingInfo& i : infos()) out.push_back(i.key);
  return out;
}

namespace {

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.7g", v);  // settings are float or 32-bit: 7 digits say it
  return buf;
}

std::string range_text(const SettingInfo& i) {
  if (i.type == SettingType::Flag) return "0 or 1";
  if (i.type == SettingType::Text) return i.choices.empty() ? "any" : join(i.choices, ", ");
  if (i.type == SettingType::Integer) return "[" + std::to_string(std::int64_t(i.min)) + ", " + std::to_string(std::int64_t(i.max)) + "]";
  return "[" + number_text(i.min) + ", " + number_text(i.max) + "]";
}

std::string value_text(const json& v) {
  if (v.is_boolean()) return v.get<bool>() ? "1" : "0";
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number_float()) return number_text(v.get<double>());
  return dump_text(v);
}

}  // namespace

namespace detail {

double setting_number(const std::string& where, const SettingInfo& info, const json& value) {
  const bool integer = info.type == SettingType::Integer;
  const std::string expected = std::string(integer ? "an integer" : "a number") + " in " + range_text(info);
  double v = 0;
  if (value.is_string()) {  // as typed on the command line: the whole text must be the number
    const std::string& text = value.get_ref<const std::string&>();
    std::size_t used = 0;
    try {
      v = std::stod(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (text.empty() || used != text.size()) throw UsageError("--set " + where + ": expected " + expected + ", got " + dump_text(value));
  } else if (value.is_number() && !value.is_boolean()) {
    v = value.get<double>();
  } else {
    throw UsageError("--set " + where + ": expected " + expected + ", got " + dump_text(value));
  }
  if (!std::isfinite(v) || (integer && v != std::floor(v)) || v < info.min || v > info.max)
    throw UsageError("--set " + where + ": expected " + expected + ", got " + dump_text(value));
  return v;
}

bool setting_flag(const std::string& where, const json& value) {
  if (value.is_boolean()) return value.get<bool>();
  if (value.is_string()) {
    const std::string& t = value.get_ref<const std::string&>();
    if (t == "1" || t == "true") return true;
    if (t == "0" || t == "false") return false;
  }
  if (value.is_number_integer() && (value.get<std::int64_t>() == 0 || value.get<std::int64_t>() == 1))
    return value.get<std::int64_t>() == 1;
  throw UsageError("--set " + where + ": expected 0, 1, true or false, got " + dump_text(value));
}

std::string setting_text(const std::string& where, const SettingInfo& info, const json& value) {
  const std::string text = value.is_string() ? value.get<std::string>() : dump_text(value);
  // Settings go into JSON keys and records, which hold UTF-8 only (a path in another encoding
  // would never match its own record).
  if (!is_utf8(text)) throw UsageError("--set " + where + ": the value is not UTF-8 text: " + dump_text(value));
  if (!info.choices.empty() && std::find(info.choices.begin(), info.choices.end(), text) == info.choices.end())
    throw UsageError("--set " + where + ": expected one of " + join(info.choices, ", ") + ", got '" + text + "'" +
                     did_you_mean(text, info.choices));
  return text;
}

void unknown_setting(const StageSettings& settings, const std::string& key) {
  const std::vector<std::string> keys = settings.keys();
  throw UsageError("--set " + settings.stage() + "." + key + ": the stage has no setting '" + key + "'" +
                   did_you_mean(key, keys) + "; its settings: " + join(keys) +
                   " (nf_gpu reconstruct --help-stage " + settings.stage() + ")");
}

}  // namespace detail

std::string describe_settings(const StageSettings& settings, bool markdown) {
  std::vector<json> defaults;
  for (const std::string& q : quality_names()) defaults.push_back(settings.values(q, json::object()));
  std::vector<std::vector<std::string>> rows;
  for (const SettingInfo& i : settings.infos()) {
    std::vector<std::string> per_quality;
    for (const json& d : defaults) per_quality.push_back(value_text(d[i.key]));
    const bool same = std::all_of(per_quality.begin(), per_quality.end(), [&](const auto& v) { return v == per_quality[0]; });
    rows.push_back({i.key, setting_type_name(i.type), range_text(i), same ? per_quality[0] : join(per_quality, " / "),
                    i.help});
  }
  const std::vector<std::string> header{"key", "type", "range", "default (" + join(quality_names(), " / ") + ")", "meaning"};
  std::ostringstream out;
  if (markdown) {
    out << "| " << join(header, " | ") << " |\n|" << std::string("---|---|---|---|---|") << "\n";
    for (const auto& r : rows) out << "| `" << r[0] << "` | " << join({r.begin() + 1, r.end()}, " | ") << " |\n";
    return out.str();
  }
  std::vector<std::size_t> width(4, 0);
  for (std::size_t c = 0; c < 4; ++c) {
    width[c] = header[c].size();
    for (const auto& r : rows) width[c] = std::max(width[c], r[c].size());
  }
  const auto line = [&](const std::vector<std::string>& r) {
    for (std::size_t c = 0; c < 4; ++c) out << r[c] << std::string(width[c] - r[c].size() + 2, ' ');
    out << r[4] << "\n";
  };
  out << "settings of stage '" << settings.stage() << "' (--set " << settings.stage() << ".KEY=VALUE):\n";
  line(header);
  for (const auto& r : rows) line(r);
  return out.str();
}

}  // namespace nf::pipeline
