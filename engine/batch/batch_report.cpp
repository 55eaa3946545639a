#include "engine/batch/batch_report.hpp"

#include <cstdio>
#include <map>
#include <sstream>

#include "engine/core/host.hpp"
#include "engine/core/text.hpp"
#include "engine/pipeline/export_stage.hpp"
#include "engine/pipeline/pipeline.hpp"
#include "engine/pipeline/stage_record.hpp"
#include "engine/pipeline/stages.hpp"

namespace nf::batch {

namespace fs = std::filesystem;

namespace {

// The scores a reader compares scenes by, where the stage measured them.
void add_scores(const std::string& stage, const json& summary, json& scores) {
  const auto number = [&](const json& j, std::initializer_list<const char*> path) -> const json* {
    const json* at = &j;
    for (const char* key : path) {
      if (!at->is_object() || !at->contains(key)) return nullptr;
      at = &(*at)[key];
    }
    return at->is_number() ? at : nullptr;
  };
  if (stage == "neus") {
    if (const json* v = number(summary, {"held_out", "psnr_in_mask_mean"})) scores["neus_held_out_psnr"] = *v;
  } else if (stage == "fur") {
    if (const json* v = number(summary, {"held_out", "orientation_error_deg"})) scores["fur_held_out_orientation_deg"] = *v;
    if (const json* v = number(summary, {"held_out", "silhouette_iou"})) scores["fur_held_out_iou"] = *v;
    if (const json* v = number(summary, {"groom", "fscore", "2cm_20deg"})) scores["fur_F_2cm"] = *v;
    if (const json* v = number(summary, {"groom", "fscore", "2mm_20deg"})) scores["fur_F_2mm"] = *v;
  } else if (stage == "knowledge") {
    if (const json* v = number(summary, {"scale", "cm_per_unit"})) scores["cm_per_unit"] = *v;
  }
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

std::string score_text(const json& scores) {
  std::string out;
  const auto add = [&](const char* key, const char* label, int digits, const char* unit) {
    if (!scores.contains(key)) return;
    if (!out.empty()) out += ", ";
    out += std::string(label) + " " + fixed(scores[key].get<double>(), digits) + unit;
  };
  add("fur_F_2cm", "F(2cm)", 1, "");
  add("fur_F_2mm", "F(2mm)", 1, "");
  add("fur_held_out_orientation_deg", "orientation", 1, "°");
  add("fur_held_out_iou", "IoU", 3, "");
  add("neus_held_out_psnr", "PSNR", 1, " dB");
  return out;
}

std::string seconds_text(const SceneRow& r) {
  std::string out;
  for (const auto& [stage, s] : r.stage_seconds) out += (out.empty() ? "" : " ") + stage + " " + fixed(s, 0);
  return out;
}

std::string markdown_cell(const std::string& text) {
  std::string out;
  for (char ch : text) out += ch == '|' ? std::string("\\|") : ch == '\n' ? std::string(" ") : std::string(1, ch);
  return out;
}

std::string relative(const std::string& path, const fs::path& to) {
  return fs::path(path).lexically_relative(fs::absolute(to)).generic_string();
}

}  // namespace

std::vector<SceneRow> scene_rows(const BatchFolder& folder) {
  std::vector<SceneRow> rows;
  const std::vector<std::string> stages = pipeline::stage_names();
  for (const BatchTask& t : folder.tasks()) {
    SceneRow r;
    r.name = t.name;
    const TaskState s = folder.state(t.name);
    r.state = s.state;
    r.attempts = s.attempts;
    r.host = s.host;
    r.job = s.job;
    r.message = s.message;
    r.log = folder.log_file(t.name).string();
    // A task of this host whose process is gone never filed its end.
    if (s.state == "running" && s.pid > 0 && s.host == host_name() && !process_alive(pid_t(s.pid))) {
      r.state = "lost";
      r.message = "its process " + std::to_string(s.pid) + " ended without filing its state; run the batch again to resume";
    }
    for (const std::string& stage : stages) {
      const auto record = pipeline::read_stage_record(pipeline::stage_record(t.work, stage));
      if (!record) continue;
      r.stage_reached = stage;
      r.stage_seconds.emplace_back(stage, record->seconds);
      add_scores(stage, record->summary, r.scores);
      if (const auto w = record->summary.find("warnings"); w != record->summary.end() && w->is_array())
        for (const json& text : *w)
          if (text.is_string()) r.warnings.push_back(stage + ": " + text.get<std::string>());
    }
    if (r.state == "running")
      for (const std::string& stage : stages)
        if (fs::exists(t.work / (stage + ".partial"))) r.stage_running = stage;
    const fs::path out = pipeline::export_outputs(t.work).dir;
    for (const char* preview : {"turntable.png", "compare_004.png"})
      if (fs::exists(out / preview)) r.previews.push_back((out / preview).string());
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator(out, ec)) {
      const std::string n = e.path().filename().string();
      if (n.rfind("compare_", 0) == 0 && e.path().extension() == ".png" && n != "compare_004.png" && r.previews.size() < 3)
        r.previews.push_back(e.path().string());
    }
    rows.push_back(std::move(r));
  }
  return rows;
}

json rows_to_json(const std::vector<SceneRow>& rows) {
  json out = json::array();
  for (const SceneRow& r : rows) {
    json seconds = json::object();
    for (const auto& [stage, s] : r.stage_seconds) seconds[stage] = s;
    out.push_back({{"name", r.name}, {"state", r.state}, {"attempts", r.attempts}, {"stage_reached", r.stage_reached},
                   {"stage_running", r.stage_running}, {"seconds", seconds}, {"scores", r.scores}, {"warnings", r.warnings}, {"host", r.host}, {"job", r.job},
                   {"message", r.message}, {"log", r.log}, {"previews", r.previews}});
  }
  return out;
}

std::string rows_to_text(const std::vector<SceneRow>& rows) {
  std::ostringstream s;
  std::size_t width = 5;
  for (const SceneRow& r : rows) width = std::max(width, r.name.size());
  char line[512];
  std::snprintf(line, sizeof line, "%-*s  %-9s %-9s %-4s %s\n", int(width), "scene", "state", "reached", "runs", "seconds per stage; scores");
  s << line;
  std::map<std::string, int> counts;
  for (const SceneRow& r : rows) {
    ++counts[r.state];
    std::snprintf(line, sizeof line, "%-*s  %-9s %-9s %-4d ", int(width), r.name.c_str(), r.state.c_str(),
                  r.stage_reached.empty() ? "-" : r.stage_reached.c_str(), r.attempts);
    s << line << seconds_text(r);
    if (!r.stage_running.empty()) s << (r.stage_seconds.empty() ? "" : " ") << "(" << r.stage_running << " running on " << r.host << ")";
    const std::string scores = score_text(r.scores);
    if (!scores.empty()) s << "; " << scores;
    s << "\n";
    if (!r.message.empty() && r.state != "done") s << std::string(width + 2, ' ') << r.message << " (log: " << r.log << ")\n";
    for (const std::string& w : r.warnings) s << std::string(width + 2, ' ') << "warning: " << w << "\n";
  }
  s << rows.size() << " scene(s):";
  for (const auto& [state, n] : counts) s << " " << n << " " << state;
  s << "\n";
  return s.str();
}

std::string rows_to_markdown(const std::vector<SceneRow>& rows, const fs::path& relative_to) {
  std::ostringstream s;
  s << "# nf_gpu batch report\n\n| scene | state | runs | stage reached | seconds per stage | scores | warnings |\n|---|---|---|---|---|---|---|\n";
  for (const SceneRow& r : rows) {
    std::string warnings;
    for (const std::string& w : r.warnings) warnings += (warnings.empty() ? "" : "; ") + w;
    if (!r.message.empty() && r.state != "done") warnings = r.message + (warnings.empty() ? "" : "; " + warnings);
    s << "| " << markdown_cell(r.name) << " | " << r.state << " | " << r.attempts << " | " << (r.stage_reached.empty() ? "-" : r.stage_reached)
      << " | " << seconds_text(r) << " | " << markdown_cell(score_text(r.scores)) << " | " << markdown_cell(warnings) << " |\n";
  }
  for (const SceneRow& r : rows) {
    if (r.previews.empty()) continue;
    s << "\n## " << r.name << "\n\n";
    for (const std::string& p : r.previews) s << "![" << fs::path(p).filename().string() << "](" << relative(p, relative_to) << ")\n";
  }
  return s.str();
}

std::string rows_to_html(const std::vector<SceneRow>& rows, const fs::path& relative_to) {
  std::ostringstream s;
  s << "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>nf_gpu batch report</title>\n"
       "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:4px 8px;"
       "vertical-align:top}img{max-width:480px;margin:4px}.failed,.lost,.stopped{color:#b00}.done{color:#070}</style></head><body>\n"
       "<h1>nf_gpu batch report</h1>\n<p>generated "
    << utc_now() << "</p>\n<table><tr><th>scene</th><th>state</th><th>runs</th><th>stage reached</th><th>seconds per stage</th>"
                    "<th>scores</th><th>warnings</th></tr>\n";
  for (const SceneRow& r : rows) {
    std::string warnings;
    for (const std::string& w : r.warnings) warnings += (warnings.empty() ? "" : "<br>") + html_escape(w);
    if (!r.message.empty() && r.state != "done") warnings = html_escape(r.message) + (warnings.empty() ? "" : "<br>" + warnings);
    s << "<tr><td><a href=\"#" << html_escape(r.name) << "\">" << html_escape(r.name) << "</a></td><td class=\"" << r.state << "\">"
      << r.state << "</td><td>" << r.attempts << "</td><td>" << (r.stage_reached.empty() ? "-" : r.stage_reached) << "</td><td>"
      << html_escape(seconds_text(r)) << "</td><td>" << html_escape(score_text(r.scores)) << "</td><td>" << warnings << "</td></tr>\n";
  }
  s << "</table>\n";
  for (const SceneRow& r : rows) {
    s << "<h2 id=\"" << html_escape(r.name) << "\">" << html_escape(r.name) << "</h2>\n";
    if (r.previews.empty()) s << "<p>no previews yet</p>\n";
    for (const std::string& p : r.previews)
      s << "<img src=\"" << html_escape(relative(p, relative_to)) << "\" alt=\"" << html_escape(fs::path(p).filename().string()) << "\">\n";
  }
  s << "</body></html>\n";
  return s.str();
}

}  // namespace nf::batch
