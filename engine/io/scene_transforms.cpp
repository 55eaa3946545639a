// nerfstudio / instant-ngp transforms.json: camera-to-world `transform_matrix` per frame (OpenGL
// axes), intrinsics fl_x fl_y cx cy w h globally or per frame (or camera_angle_x), file_path and
// mask_path relative to the file. Lens distortion is refused with a clear message. Every value is
// read through JsonField, so a wrong type names its path ("frames[3].transform_matrix[1][2]").
#include <cmath>
#include <optional>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/io/scene.hpp"

namespace nf::io {
namespace {

// The frame's own value, else the file-wide one (intrinsics may be given either way).
std::optional<JsonField> lookup(const JsonField& frame, const JsonField& top, const char* key) {
  if (auto v = frame.find(key)) return v;
  return top.find(key);
}

// NaN `fallback`: the field is required.
double number(const JsonField& frame, const JsonField& top, const char* key, const std::string& where,
              double fallback = NAN) {
  if (const auto v = lookup(frame, top, key)) return v->number();
  if (std::isnan(fallback)) throw InputError(where + ": field '" + key + "' is missing");
  return fallback;
}

// Image sizes become integers: refuse what the cast could not hold (Scene::validate checks the range).
std::uint32_t pixels(const JsonField& frame, const JsonField& top, const char* key, const std::string& where) {
  const auto v = lookup(frame, top, key);
  if (!v) throw InputError(where + ": field '" + key + "' is missing");
  const double n = v->number();
  if (!(n >= 0 && n <= 4294967295.0) || n != std::floor(n))
    v->fail("expected a whole number of pixels, got " + describe_json(v->value()));
  return std::uint32_t(n);
}

}  // namespace

Scene read_transforms_json(const std::filesystem::path& file) {
  const std::string source = file.string();
  const json doc = read_json_file(file);
  const JsonField top(doc, source);
  if (!top.value().is_object() || !top.has("frames") || !top.value()["frames"].is_array())
    throw InputError(source + ": field 'frames' is missing");
  Scene scene;
  scene.root = file.parent_path();
  if (const auto cm = top.find("cm_per_unit")) {
    scene.cm_per_unit = cm->number();
    if (!(std::isfinite(*scene.cm_per_unit) && *scene.cm_per_unit > 0)) cm->fail("expected a positive number of cm per unit");
  }
  const JsonField frames = top.at("frames");
  for (std::size_t index = 0; index < frames.size(); ++index) {
    const JsonField f = frames.at(index);
    const std::string where = source + ": " + f.path();
    for (const char* k : {"k1", "k2", "k3", "k4", "p1", "p2"})
      if (number(f, top, k, where, 0.0) != 0.0)
        throw InputError(where + ": lens distortion ('" + std::string(k) +
                         "') is not supported; undistort the images first (e.g. with COLMAP's image_undistorter)");
    Camera c;
    c.width = pixels(f, top, "w", where);
    c.height = pixels(f, top, "h", where);
    if (f.has("fl_x") || top.has("fl_x")) {
      c.fx = number(f, top, "fl_x", where);
      c.fy = number(f, top, "fl_y", where, c.fx);
    } else {
      const double angle = number(f, top, "camera_angle_x", where);
      c.fx = c.fy = 0.5 * c.width / std::tan(0.5 * angle);
    }
    c.cx = number(f, top, "cx", where, 0.5 * c.width);
    c.cy = number(f, top, "cy", where, 0.5 * c.height);
    const JsonField m = f.at("transform_matrix");
    if (m.size() < 3) m.fail("expected 3 or 4 rows of 4 numbers (3x4 or 4x4), got " + std::to_string(m.size()) + " rows");
    for (std::size_t r = 0; r < 3; ++r)
      for (std::size_t col = 0; col < 4; ++col) c.camera_to_world[int(col)][int(r)] = m.at(r).at(col).number();
    const std::string path = f.at("file_path").string();
    c.image = scene.root / path;
    c.name = std::filesystem::path(path).stem().string();
    if (const auto mask = f.find("mask_path")) c.mask = scene.root / mask->string();
    scene.cameras.push_back(c);
  }
  scene.validate(source);
  return scene;
}

void write_transforms_json(const std::filesystem::path& file, const Scene& scene) {
  scene.validate(file.string());
  json top{{"frames", json::array()}};
  if (scene.cm_per_unit) top["cm_per_unit"] = *scene.cm_per_unit;
  const auto relative = [&](const std::filesystem::path& p) {
    return p.empty() ? std::string() : std::filesystem::relative(p, file.parent_path()).generic_string();
  };
  for (const Camera& c : scene.cameras) {
    json m = json::array();
    for (int r = 0; r < 4; ++r) {
      json row = json::array();
      for (int col = 0; col < 4; ++col) row.push_back(c.camera_to_world[col][r]);
      m.push_back(row);
    }
    json f{{"file_path", relative(c.image)}, {"transform_matrix", m}, {"fl_x", c.fx}, {"fl_y", c.fy},
           {"cx", c.cx},  {"cy", c.cy}, {"w", c.width}, {"h", c.height}};
    if (!c.mask.empty()) f["mask_path"] = relative(c.mask);
    top["frames"].push_back(f);
  }
  write_file_atomic(file, top.dump(2) + "\n");
}

}  // namespace nf::io
