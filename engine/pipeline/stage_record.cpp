#include "engine/pipeline/stage_record.hpp"

#include <fstream>

namespace nf::pipeline {

json read_json_or_null(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) return json();
  try {
    return json::parse(in);
  } catch (const json::exception&) {
    return json();
  }
}

std::optional<StageRecord> read_stage_record(const std::filesystem::path& file) {
  const json j = read_json_or_null(file);
  if (!j.is_object() || !j.contains("key")) return std::nullopt;
  StageRecord r;
  r.key = j["key"];
  // Fields of the wrong type keep their defaults: they only inform the user.
  if (const auto s = j.find("summary"); s != j.end() && s->is_object()) r.summary = *s;
  if (const auto f = j.find("finished"); f != j.end() && f->is_string()) r.finished = f->get<std::string>();
  if (const auto t = j.find("seconds"); t != j.end() && t->is_number()) r.seconds = t->get<double>();
  if (const auto q = j.find("quality"); q != j.end() && q->is_string()) r.quality = q->get<std::string>();
  if (const auto s = j.find("settings"); s != j.end() && s->is_object()) r.settings = *s;
  return r;
}

}  // namespace nf::pipeline
