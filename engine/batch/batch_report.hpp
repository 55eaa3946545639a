#pragma once
// `nf_gpu batch status` and `batch report`: one row per scene from its task state and its WORK
// folder's stage records (stage reached, seconds per stage, scores, warnings, previews).
#include <string>
#include <vector>

#include "engine/batch/batch_folder.hpp"

namespace nf::batch {

struct SceneRow {
  std::string name, state, stage_reached, host, job, message, log;
  std::string stage_running;  // the stage a running task is in ("" otherwise)
  int attempts = 0;
  std::vector<std::pair<std::string, double>> stage_seconds;  // the stages finished, in order
  json scores = json::object();                                // what the stages measured
  std::vector<std::string> warnings;
  std::vector<std::string> previews;                           // absolute paths of PNGs
};

std::vector<SceneRow> scene_rows(const BatchFolder& folder);

json rows_to_json(const std::vector<SceneRow>& rows);
std::string rows_to_text(const std::vector<SceneRow>& rows);      // the terminal's table
std::string rows_to_markdown(const std::vector<SceneRow>& rows, const std::filesystem::path& relative_to);
std::string rows_to_html(const std::vector<SceneRow>& rows, const std::filesystem::path& relative_to);

}  // namespace nf::batch
