#include "engine/batch/manifest.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <set>

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/pipeline/stages.hpp"

namespace nf::batch {

namespace fs = std::filesystem;

namespace {

// A setting value as reconstruct's --set takes it: the text typed (strings unquoted).
std::string setting_text(const json& value) { return value.is_string() ? value.get<std::string>() : dump_text(value); }

// {"fur.steps": 300} or {"fur": {"steps": 300}} -> "fur.steps=300", ...
void add_settings(const io::JsonField& settings, std::vector<std::string>& out) {
  if (!settings.value().is_object()) settings.fail("expected an object of \"stage.key\": value");
  for (const auto& [key, value] : settings.value().items()) {
    if (value.is_object()) {
      for (const auto& [inner, v] : value.items()) out.push_back(key + "." + inner + "=" + setting_text(v));
    } else if (key.find('.') == std::string::npos) {
      settings.fail("'" + key + "' is not \"stage.key\" (e.g. \"fur.steps\")");
    } else {
      out.push_back(key + "=" + setting_text(value));
    }
  }
}

fs::path resolve(const fs::path& base, const std::string& text) {
  const fs::path p(text);
  return (p.is_absolute() ? p : base / p).lexically_normal();
}

std::string default_name(const fs::path& scene) {
  // A scene given as its transforms.json is named by its folder.
  const fs::path folder = scene.has_extension() ? scene.parent_path() : scene;
  const std::string name = folder.filename().string();
  return name.empty() ? "scene" : name;
}

struct Defaults {
  std::string quality = "default";
  double scene_scale = 0;
  std::vector<std::string> settings;
};

double scale_value(double v, const std::string& where) {
  if (!std::isfinite(v) || v <= 0) throw InputError(where + ": scene_scale must be a positive number of cm per scene unit");
  return v;
}

std::vector<BatchTask> read_json_manifest(const fs::path& file, const fs::path& base) {
  const json root = io::read_json_file(file);
  const io::JsonField top(root, file.string());
  Defaults defaults;
  const json* scenes = &root;
  std::string scenes_path;
  if (root.is_object()) {
    for (const auto& [key, value] : root.items())
      if (key != "defaults" && key != "scenes") top.fail("unknown field '" + key + "'" + did_you_mean(key, {"defaults", "scenes"}));
    if (const auto d = top.find("defaults")) {
      if (!d->value().is_object()) d->fail("expected an object with \"quality\", \"scene_scale\" or \"settings\"");
      for (const auto& [key, value] : d->value().items())
        if (key != "quality" && key != "scene_scale" && key != "settings")
          d->fail("unknown field '" + key + "'" + did_you_mean(key, {"quality", "scene_scale", "settings"}));
      if (const auto q = d->find("quality")) defaults.quality = q->string();
      if (const auto s = d->find("scene_scale")) defaults.scene_scale = scale_value(s->number(), file.string() + ": defaults");
      if (const auto s = d->find("settings")) add_settings(*s, defaults.settings);
    }
    scenes = &top.at("scenes").value();
    scenes_path = "scenes";
  }
  if (!scenes->is_array()) top.fail("expected a list of scenes, or an object with \"scenes\" (and \"defaults\")");
  const io::JsonField list(*scenes, file.string(), scenes_path);
  std::vector<BatchTask> tasks;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const io::JsonField entry = list.at(i);
    if (!entry.value().is_object()) entry.fail("expected an object with \"scene\" (and \"work\", \"settings\")");
    for (const auto& [key, value] : entry.value().items())
      if (key != "scene" && key != "work" && key != "name" && key != "quality" && key != "scene_scale" && key != "settings")
        entry.fail("unknown field '" + key + "'" + did_you_mean(key, {"scene", "work", "name", "quality", "scene_scale", "settings"}));
    BatchTask t;
    t.origin = entry.path();
    t.scene = resolve(base, entry.at("scene").string());
    t.name = entry.has("name") ? entry.at("name").string() : default_name(t.scene);
    t.work = entry.has("work") ? resolve(base, entry.at("work").string()) : (base / "work" / t.name).lexically_normal();
    t.quality = entry.has("quality") ? entry.at("quality").string() : defaults.quality;
    t.scene_scale = entry.has("scene_scale") ? scale_value(entry.at("scene_scale").number(), file.string() + ": " + entry.path())
                                             : defaults.scene_scale;
    t.settings = defaults.settings;
    if (const auto s = entry.find("settings")) add_settings(*s, t.settings);
    tasks.push_back(std::move(t));
  }
  return tasks;
}

// One CSV record: fields split on commas, "quoted" fields may hold commas and "" for a quote.
std::vector<std::string> csv_fields(const std::string& line, const std::string& where) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char ch = line[i];
    if (quoted) {
      if (ch == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (ch == '"') {
        quoted = false;
      } else {
        fields.back() += ch;
      }
    } else if (ch == '"') {
      quoted = true;
    } else if (ch == ',') {
      fields.emplace_back();
    } else if (ch != '\r') {
      fields.back() += ch;
    }
  }
  if (quoted) throw InputError(where + ": a quoted field is not closed");
  for (std::string& f : fields) {
    const auto b = f.find_first_not_of(" \t"), e = f.find_last_not_of(" \t");
    f = b == std::string::npos ? "" : f.substr(b, e - b + 1);
  }
  return fields;
}

std::vector<BatchTask> read_csv_manifest(const fs::path& file, const fs::path& base) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot open");
  std::string line;
  std::vector<std::string> header;
  std::vector<BatchTask> tasks;
  for (int row = 1; std::getline(in, line); ++row) {
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    const std::string where = file.string() + ": line " + std::to_string(row);
    // The manifest's text goes into batch.json and the stage keys, which hold UTF-8 only.
    if (!is_utf8(line)) throw InputError(where + ": not UTF-8 text (save the manifest as UTF-8)");
    std::vector<std::string> fields = csv_fields(line, where);
    if (header.empty()) {
      header = fields;
      std::set<std::string> seen;
      for (const std::string& h : header) {
        if (!seen.insert(h).second) throw InputError(where + ": the column '" + h + "' appears twice");
        if (h != "scene" && h != "work" && h != "name" && h != "quality" && h != "scene_scale" && h.find('.') == std::string::npos)
          throw InputError(where + ": the column '" + h + "' is neither scene, work, name, quality, scene_scale nor a setting \"stage.key\"" +
                           did_you_mean(h, {"scene", "work", "name", "quality", "scene_scale"}));
      }
      if (!seen.count("scene")) throw InputError(where + ": the header has no 'scene' column");
      continue;
    }
    if (fields.size() != header.size())
      throw InputError(where + ": " + std::to_string(fields.size()) + " fields where the header has " + std::to_string(header.size()));
    BatchTask t;
    t.origin = "line " + std::to_string(row);
    std::string work;
    for (std::size_t c = 0; c < header.size(); ++c) {
      const std::string& h = header[c];
      const std::string& v = fields[c];
      if (h == "scene") {
        if (v.empty()) throw InputError(where + ": the scene is empty");
        t.scene = resolve(base, v);
      } else if (h == "work") {
        work = v;
      } else if (h == "name") {
        t.name = v;
      } else if (h == "quality") {
        if (!v.empty()) t.quality = v;
      } else if (h == "scene_scale") {
        if (!v.empty()) {
          char* end = nullptr;
          const double s = std::strtod(v.c_str(), &end);
          if (end == v.c_str() || *end != '\0') throw InputError(where + ": scene_scale '" + v + "' is not a number");
          t.scene_scale = scale_value(s, where);
        }
      } else if (!v.empty()) {
        t.settings.push_back(h + "=" + v);
      }
    }
    if (t.name.empty()) t.name = default_name(t.scene);
    t.work = work.empty() ? (base / "work" / t.name).lexically_normal() : resolve(base, work);
    tasks.push_back(std::move(t));
  }
  return tasks;
}

}  // namespace

std::vector<BatchTask> read_manifest(const fs::path& file) {
  if (!fs::is_regular_file(file)) throw InputError("the manifest '" + file.string() + "' is not a file");
  const fs::path base = fs::absolute(file).parent_path();
  const std::string ext = to_lower(file.extension().string());
  std::vector<BatchTask> tasks;
  if (ext == ".json") tasks = read_json_manifest(file, base);
  else if (ext == ".csv") tasks = read_csv_manifest(file, base);
  else throw InputError("the manifest '" + file.string() + "' is neither .json nor .csv");
  if (tasks.empty()) throw InputError(file.string() + ": no scenes");
  std::map<std::string, std::string> names, works;
  for (const BatchTask& t : tasks) {
    if (t.name.empty() || t.name.find_first_of("/\\") != std::string::npos || t.name == "." || t.name == ".." ||
        t.name.find_first_of("\n\r\t") != std::string::npos)
      throw InputError(file.string() + ": " + t.origin + ": the name '" + t.name + "' cannot be a file name");
    if (!names.emplace(t.name, t.scene.string()).second)
      throw InputError(file.string() + ": two scenes are named '" + t.name + "' (" + names[t.name] + ", " + t.scene.string() +
                       "): give each a \"name\"");
    if (!works.emplace(t.work.string(), t.name).second)
      throw InputError(file.string() + ": '" + t.name + "' and '" + works[t.work.string()] + "' share the WORK folder '" +
                       t.work.string() + "': each scene needs its own");
  }
  for (const BatchTask& t : tasks) {
    // What reconstruct would refuse, refused now, before anything is submitted.
    try {
      (void)pipeline::check_reconstruct_options(reconstruct_options(t));
    } catch (const Error& e) {
      throw InputError(file.string() + ": " + t.origin + " (scene '" + t.name + "'): " + e.what());
    }
  }
  return tasks;
}

pipeline::ReconstructOptions reconstruct_options(const BatchTask& task) {
  pipeline::ReconstructOptions o;
  o.scene = task.scene;
  o.work = task.work;
  o.quality = task.quality;
  o.settings = task.settings;
  o.scene_scale = task.scene_scale;
  return o;
}

json to_json(const BatchTask& t) {
  return {{"name", t.name}, {"scene", t.scene.string()}, {"work", t.work.string()}, {"quality", t.quality},
          {"scene_scale", t.scene_scale}, {"settings", t.settings}};
}

BatchTask task_from_json(const json& j) {
  BatchTask t;
  t.name = j.at("name").get<std::string>();
  t.scene = j.at("scene").get<std::string>();
  t.work = j.at("work").get<std::string>();
  t.quality = j.at("quality").get<std::string>();
  t.scene_scale = j.at("scene_scale").get<double>();
  t.settings = j.at("settings").get<std::vector<std::string>>();
  return t;
}

}  // namespace nf::batch
