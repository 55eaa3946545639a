#pragma once
// WORK/<stage>/stage.json, the record that lets a rerun skip an unchanged stage, and the key file of
// a stage's checkpoint folder (WORK/.resume/<stage>/key.json). Both are nf_gpu's own files, but a
// disk, an editor or a kill can leave anything in them: an unreadable or odd record counts as no
// record, so the stage simply runs again.
#include <filesystem>
#include <optional>
#include <string>

#include "engine/core/json.hpp"

namespace nf::pipeline {

struct StageRecord {
  json key;                          // what the stage was run with (parameters + input hashes)
  json summary = json::object();     // the stage's own summary (an object)
  std::string finished = "?";        // UTC time of completion
  double seconds = 0;
  // What the result was made with, beside its key: the quality and the stage's resolved settings
  // (empty and null in records written before they were kept).
  std::string quality;
  json settings;
};

// nullopt when the file is missing, not JSON or not an object with a key.
std::optional<StageRecord> read_stage_record(const std::filesystem::path& file);
// The JSON in `file`, or null when it is missing or unreadable.
json read_json_or_null(const std::filesystem::path& file);

}  // namespace nf::pipeline
