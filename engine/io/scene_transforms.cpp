// nerfstudio / instant-ngp transforms.json: camera-to-world `transform_matrix` per frame (OpenGL
// axes), intrinsics fl_x fl_y cx cy w h globally or per frame (or camera_angle_x), file_path and
// mask_path relative to the file. Lens distortion is refused with a clear message.
#include <fstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/json.hpp"
#include "engine/io/scene.hpp"

namespace nf::io {
namespace {

double number(const json& frame, const json& top, const char* key, const std::string& where, double fallback = NAN) {
  if (frame.contains(key)) return frame[key].get<double>();
  if (top.contains(key)) return top[key].get<double>();
  if (std::isnan(fallback)) throw InputError(where + ": field '" + key + "' is missing");
  return fallback;
}

}  // namespace

Scene read_transforms_json(const std::filesystem::path& file) {
  const std::string source = file.string();
  std::ifstream in(file);
  if (!in) throw InputError(source + ": cannot open");
  json top;
  try {
    top = json::parse(in);
  } catch (const json::exception& e) {
    throw InputError(source + ": not valid JSON (" + e.what() + ")");
  }
  if (!top.contains("frames") || !top["frames"].is_array()) throw InputError(source + ": field 'frames' is missing");
  Scene scene;
  scene.root = file.parent_path();
  if (top.contains("cm_per_unit")) scene.cm_per_unit = top["cm_per_unit"].get<double>();
  std::size_t index = 0;
  for (const json& f : top["frames"]) {
    const std::string where = source + ": frames[" + std::to_string(index++) + "]";
    try {
      for (const char* k : {"k1", "k2", "k3", "k4", "p1", "p2"})
        if (number(f, top, k, where, 0.0) != 0.0)
          throw InputError(where + ": lens distortion ('" + std::string(k) +
                           "') is not supported; undistort the images first (e.g. with COLMAP's image_undistorter)");
      Camera c;
      c.width = std::uint32_t(number(f, top, "w", where));
      c.height = std::uint32_t(number(f, top, "h", where));
      if (f.contains("fl_x") || top.contains("fl_x")) {
        c.fx = number(f, top, "fl_x", where);
        c.fy = number(f, top, "fl_y", where, c.fx);
      } else {
        const double angle = number(f, top, "camera_angle_x", where);
        c.fx = c.fy = 0.5 * c.width / std::tan(0.5 * angle);
      }
      c.cx = number(f, top, "cx", where, 0.5 * c.width);
      c.cy = number(f, top, "cy", where, 0.5 * c.height);
      const json& m = f.at("transform_matrix");
      if (!m.is_array() || m.size() < 3) throw InputError(where + ": transform_matrix must be 3x4 or 4x4");
      for (int r = 0; r < 3; ++r)
        for (int col = 0; col < 4; ++col) c.camera_to_world[col][r] = m.at(r).at(col).get<double>();
      const std::string path = f.at("file_path").get<std::string>();
      c.image = scene.root / path;
      c.name = std::filesystem::path(path).stem().string();
      if (f.contains("mask_path")) c.mask = scene.root / f["mask_path"].get<std::string>();
      scene.cameras.push_back(c);
    } catch (const json::exception& e) {
      throw InputError(where + ": " + e.what());
    }
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
