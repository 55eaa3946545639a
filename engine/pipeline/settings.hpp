#pragma once
// Stage settings (`--set stage.key=value`), declared once per stage: name, type, range, one-line
// help and where the value lives in the stage's settings struct. The one declaration drives
// parsing, validation (before any stage runs), the stage key (through the resolved values),
// the error messages and `nf_gpu reconstruct --help-stage STAGE` (and the README table made from it).
//
//   SettingsSchema<NeusSettings> schema("neus", [](const std::string& quality) { return ...; });
//   schema.add("steps", [](NeusSettings& s) -> auto& { return s.training.steps; }, 1, 1e7, "training steps");
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/core/json.hpp"

namespace nf::pipeline {

// The quality presets every stage maps to its own defaults (`--quality`).
const std::vector<std::string>& quality_names();

enum class SettingType { Integer, Real, Flag, Text };
const char* setting_type_name(SettingType type);

struct SettingInfo {
  std::string key;
  SettingType type = SettingType::Real;
  double min = 0, max = 0;           // numbers: the inclusive range
  std::vector<std::string> choices;  // text: the allowed values (empty: any text)
  std::string help;
};

// What the pipeline needs of a stage's settings, whatever the struct behind them.
class StageSettings {
 public:
  virtual ~StageSettings() = default;
  virtual const std::string& stage() const = 0;
  virtual const std::vector<SettingInfo>& infos() const = 0;
  // Every setting's effective value at `quality` with `overrides` ({"key": value}) applied.
  // Throws UsageError naming "stage.key" for an unknown key (with a "did you mean"), a value of the
  // wrong type or out of range, or a combination the stage refuses.
  virtual json values(const std::string& quality, const json& overrides) const = 0;
  std::vector<std::string> keys() const;
};

namespace detail {
// Converts one --set value to T, or throws UsageError naming "stage.key", the expectation and the value.
double setting_number(const std::string& where, const SettingInfo& info, const json& value);
bool setting_flag(const std::string& where, const json& value);
std::string setting_text(const std::string& where, const SettingInfo& info, const json& value);
[[noreturn]] void unknown_setting(const StageSettings& settings, const std::string& key);
}  // namespace detail

template <class S>
class SettingsSchema final : public StageSettings {
 public:
  SettingsSchema(std::string stage, std::function<S(const std::string& quality)> defaults)
      : stage_(std::move(stage)), defaults_(std::move(defaults)) {}

  // A number or flag; `field` returns a reference to the member inside S. Integers and reals are
  // checked against [min, max]; flags ignore the range.
  template <class Field>
  SettingsSchema& add(std::string key, Field field, double min, double max, std::string help) {
    using T = std::remove_reference_t<std::invoke_result_t<Field, S&>>;
    static_assert(std::is_arithmetic_v<T>, "use text() for strings");
    SettingInfo info{std::move(key),
                     std::is_same_v<T, bool> ? SettingType::Flag
                     : std::is_integral_v<T> ? SettingType::Integer
                                             : SettingType::Real,
                     min, max, {}, std::move(help)};
    entries_.push_back({info,
                        [field, info, where = stage_ + "." + info.key](S& s, const json& v) {
                          if constexpr (std::is_same_v<T, bool>)
                            field(s) = detail::setting_flag(where, v);
                          else
                            field(s) = static_cast<T>(detail::setting_number(where, info, v));
                        },
                        [field](S& s) { return json(field(s)); }});
    infos_.push_back(info);
    return *this;
  }

  // A text setting, optionally restricted to `choices`.
  template <class Field>
  SettingsSchema& text(std::string key, Field field, std::vector<std::string> choices, std::string help) {
    SettingInfo info{std::move(key), SettingType::Text, 0, 0, std::move(choices), std::move(help)};
    entries_.push_back({info,
                        [field, info, where = stage_ + "." + info.key](S& s, const json& v) {
                          field(s) = detail::setting_text(where, info, v);
                        },
                        [field](S& s) { return json(field(s)); }});
    infos_.push_back(info);
    return *this;
  }

  // A check of the whole struct after the overrides (e.g. one count below another). It throws
  // nf::Error with a message that names the settings; the schema reports it as a usage error.
  SettingsSchema& check(std::function<void(const S&)> whole) {
    checks_.push_back(std::move(whole));
    return *this;
  }

  S resolve(const std::string& quality, const json& overrides) const {
    S s = defaults_(quality);
    if (!overrides.is_null() && !overrides.is_object())
      throw UsageError("--set " + stage_ + ": expected key=value pairs");
    if (overrides.is_object())
      for (const auto& [key, value] : overrides.items()) entry(key).set(s, value);
    for (const auto& c : checks_) {
      try {
        c(s);
      } catch (const Error& e) {
        throw UsageError("--set " + stage_ + ": " + e.what());
      }
    }
    return s;
  }

  const std::string& stage() const override { return stage_; }
  const std::vector<SettingInfo>& infos() const override { return infos_; }
  json values(const std::string& quality, const json& overrides) const override {
    S s = resolve(quality, overrides);
    json out = json::object();
    for (const Entry& e : entries_) out[e.info.key] = e.get(s);
    return out;
  }

 private:
  struct Entry {
    SettingInfo info;
    std::function<void(S&, const json&)> set;
    std::function<json(S&)> get;
  };
  const Entry& entry(const std::string& key) const {
    for (const Entry& e : entries_)
      if (e.info.key == key) return e;
    detail::unknown_setting(*this, key);
  }

  std::string stage_;
  std::function<S(const std::string&)> defaults_;
  std::vector<Entry> entries_;
  std::vector<SettingInfo> infos_;
  std::vector<std::function<void(const S&)>> checks_;
};

// The settings of a stage as a table for people: key, type, range, the default at each quality,
// help. Markdown when `markdown` (the README's table), aligned text otherwise.
std::string describe_settings(const StageSettings& settings, bool markdown);

}  // namespace nf::pipeline
