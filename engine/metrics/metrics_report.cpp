#include "engine/metrics/metrics_report.hpp"

#include <cmath>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/io/file_frame.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/metrics/surface_metrics.hpp"

namespace nf::metrics {
namespace fs = std::filesystem;
namespace {

// cm_per_unit of a declaration file, or nullopt when the file does not exist.
std::optional<double> scale_in(const fs::path& file) {
  if (!fs::exists(file)) return std::nullopt;
  std::ifstream in(file);
  const json j = json::parse(in, nullptr, false);
  if (!j.is_object() || !j.contains("cm_per_unit")) {
    if (file.filename() == "scene.json") return std::nullopt;  // some other tool's scene.json: says nothing
    throw InputError(file.string() + ": expected a JSON object with cm_per_unit");
  }
  const json v = j["cm_per_unit"];
  if (!v.is_number() || !(v.get<double>() > 0) || !std::isfinite(v.get<double>()))
    throw InputError(file.string() + ": cm_per_unit: expected a positive number, got " + v.dump());
  return v.get<double>();
}

// The files' points in their common frame (io::common_frame): an export-frame file compared with a
// scene's comes back into the scene's frame, or is refused saying what to compare.
struct Framed {
  io::CommonFrame common;
  std::vector<std::filesystem::path> files;
  const glm::dmat4& map_of(const fs::path& f) const {
    return common.to_common[std::size_t(std::find(files.begin(), files.end(), f) - files.begin())];
  }
  io::StrandSet strands(const fs::path& f) const {
    io::StrandSet s = io::read_strands(f);
    io::transform_points(s.points, map_of(f));
    return s;
  }
  geometry::Mesh mesh(const fs::path& f) const {
    geometry::Mesh m = io::read_mesh(f);
    io::transform_points(m.positions, map_of(f));
    if (map_of(f) != glm::dmat4(1.0)) m.normals.clear();  // not read by the metrics; stale after the map
    return m;
  }
};

Framed framed(const std::vector<fs::path>& given) {
  Framed f;
  for (const fs::path& p : given)
    if (!p.empty()) f.files.push_back(p);
  f.common = io::common_frame(f.files);
  return f;
}

}  // namespace

std::optional<double> declared_scale(const std::vector<fs::path>& files, std::string* source) {
  std::optional<double> found;
  std::string found_in;
  for (const fs::path& f : files) {
    if (f.empty()) continue;
    for (const char* name : {"scale.json", "scene.json"}) {
      const fs::path declaration = fs::absolute(f).parent_path() / name;
      const std::optional<double> s = scale_in(declaration);
      if (!s) continue;
      if (found && std::abs(*found - *s) > 1e-9 * *found)
        throw InputError("the files disagree about their unit: " + found_in + " says " + std::to_string(*found) +
                         " cm per unit, " + declaration.string() + " says " + std::to_string(*s) +
                         "; pass --scale to choose");
      if (!found) found = s, found_in = declaration.string();
    }
  }
  if (found && source) *source = found_in;
  return found;
}

double resolve_scale(const MetricsRequest& r, std::string* source, bool metres) {
  std::string declared_in;
  const std::optional<double> declared = declared_scale({r.pred, r.gt, r.outer, r.mesh, r.reference}, &declared_in);
  if (r.scale) {
    if (!(*r.scale > 0) || !std::isfinite(*r.scale)) throw UsageError("--scale must be a positive number of cm per unit");
    if (declared && std::abs(*declared - *r.scale) > 1e-9 * *declared)
      log::warn("metrics: --scale ", *r.scale, " differs from the ", *declared, " cm per unit that ", declared_in,
                " declares; using --scale");
    if (source) *source = "--scale";
    return *r.scale;
  }
  if (metres) {  // the export frame is in metres, whatever a scale.json beside the files says of the scene
    if (source) *source = "the export frame (metres)";
    return 100.0;
  }
  if (declared) {
    if (source) *source = declared_in;
    return *declared;
  }
  throw UsageError("metrics: the files do not say their unit (no scale.json or synth gt/scene.json beside them): pass "
                   "--scale CM_PER_UNIT, e.g. --scale 100 for metres, --scale 0.1 for millimetres");
}

std::vector<MatchThreshold> parse_thresholds(const std::string& text) {
  if (text == "cm") return default_thresholds();
  if (text == "mm") return {{0.2, 20}, {0.3, 30}, {0.4, 40}};
  std::vector<MatchThreshold> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string entry = text.substr(start, end - start);
    start = end + 1;
    const auto bad = [&](const std::string& why) {
      return UsageError("--thresholds '" + entry + "': " + why + " (expected DISTANCE:ANGLE such as 2cm:20 or 3mm:30, "
                        "or the sets cm and mm)");
    };
    if (entry.empty()) throw bad("an empty entry");
    const std::size_t colon = entry.find(':');
    if (colon == std::string::npos) throw bad("no ':' between distance and angle");
    const std::string distance = entry.substr(0, colon), angle = entry.substr(colon + 1);
    double to_cm = 0;
    std::string number;
    for (const auto& [unit, factor] : {std::pair{"mm", 0.1}, std::pair{"cm", 1.0}, std::pair{"m", 100.0}})
      if (distance.size() > std::string(unit).size() && distance.ends_with(unit)) {
        to_cm = factor, number = distance.substr(0, distance.size() - std::string(unit).size());
        break;
      }
    if (to_cm == 0) throw bad("the distance needs a unit: mm, cm or m");
    std::size_t used = 0, used_angle = 0;
    double d = 0, a = 0;
    try {
      d = std::stod(number, &used);
      a = std::stod(angle, &used_angle);
    } catch (const std::exception&) {
      throw bad("not a number");
    }
    if (used != number.size() || used_angle != angle.size()) throw bad("not a number");
    if (!(d > 0) || !std::isfinite(d)) throw bad("the distance must be positive");
    if (!(a > 0 && a <= 180)) throw bad("the angle must lie in (0, 180] degrees");
    out.push_back({d * to_cm, a});
    if (end == text.size()) break;
  }
  return out;
}

json strand_report(const MetricsRequest& r) {
  const Framed frame = framed({r.pred, r.gt, r.outer});
  std::string source;
  const double scale = resolve_scale(r, &source, frame.common.frame == io::FileFrame::exported);
  const std::vector<MatchThreshold> thresholds = parse_thresholds(r.thresholds);
  const StrandSample pred = sample_strands(frame.strands(r.pred), r.strands, r.points, r.seed);
  json out{{"pred", r.pred.string()}, {"strands", pred.strands}, {"points_per_strand", pred.points},
           {"cm_per_unit", scale}, {"scale_source", source},
           {"consistency", to_json(consistency_metrics(pred, scale))}};
  if (!r.gt.empty()) {
    const StrandSample gt = sample_strands(frame.strands(r.gt), r.strands, r.points, r.seed + 1);
    out["gt"] = r.gt.string();
    out["match"] = to_json(match_scores(pred, gt, thresholds, scale));
  }
  if (!r.outer.empty()) out["tips_to_outer"] = to_json(tip_chamfer(pred, frame.mesh(r.outer), scale));
  out["frame"] = frame.common.frame == io::FileFrame::exported ? "export" : "scene";
  json moved = json::array();
  for (std::size_t i = 0; i < frame.files.size(); ++i)
    if (frame.common.moved[i]) moved.push_back(frame.files[i].string());
  if (!moved.empty()) out["brought_back_from_export"] = moved;
  return out;
}

json surface_report(const MetricsRequest& r) {
  const Framed frame = framed({r.mesh, r.reference});
  std::string source;
  const double scale = resolve_scale(r, &source, frame.common.frame == io::FileFrame::exported);
  const SurfaceMetrics m = surface_metrics(frame.mesh(r.mesh), frame.mesh(r.reference), scale, r.fscore_mm);
  return {{"mesh", r.mesh.string()}, {"reference", r.reference.string()}, {"cm_per_unit", scale},
          {"scale_source", source}, {"frame", frame.common.frame == io::FileFrame::exported ? "export" : "scene"},
          {"surface", to_json(m)}};
}

}  // namespace nf::metrics
