#include "engine/prepare/known_distance.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "engine/core/error.hpp"

namespace nf::prepare {

namespace fs = std::filesystem;

namespace {

constexpr double kMaxReprojectionPx = 8;   // beyond it the picks are not of one point
constexpr double kMinRayAngleDeg = 2;      // below it depth along the rays is not determined

}  // namespace

KnownDistance read_known_distance(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError("--known-distance " + file.string() + ": cannot open");
  const json j = json::parse(in, nullptr, false);
  const std::string where = "--known-distance " + file.string();
  if (!j.is_object()) throw InputError(where + ": not a JSON object (see nf_gpu help prepare for its form)");
  KnownDistance k;
  if (!j.contains("cm") || !j["cm"].is_number() || !(j["cm"].get<double>() > 0) || !std::isfinite(j["cm"].get<double>()))
    throw InputError(where + ": \"cm\": expected the distance between the two points in cm, a positive number");
  k.cm = j["cm"].get<double>();
  if (!j.contains("points") || !j["points"].is_array() || j["points"].size() != 2)
    throw InputError(where + ": \"points\": expected a list of two points, each {\"photo name\": [x, y], ...}");
  for (std::size_t p = 0; p < 2; ++p) {
    const json& point = j["points"][p];
    const std::string at = where + ": points[" + std::to_string(p) + "]";
    if (!point.is_object() || point.size() < 2) throw InputError(at + ": expected the point's pixel in two or more photos, {\"photo name\": [x, y], ...}");
    std::map<std::string, glm::dvec2> picks;
    for (const auto& [photo, xy] : point.items()) {
      if (!xy.is_array() || xy.size() != 2 || !xy[0].is_number() || !xy[1].is_number())
        throw InputError(at + "[\"" + photo + "\"]: expected [x, y] in pixels");
      picks[photo] = {xy[0].get<double>(), xy[1].get<double>()};
    }
    k.points.push_back(std::move(picks));
  }
  return k;
}

glm::dvec2 Lens::normalised(const glm::dvec2& pixel) const {
  const std::vector<double>& p = params;
  double fx, fy, cx, cy, k1 = 0, k2 = 0, p1 = 0, p2 = 0;
  if (model == "SIMPLE_PINHOLE" && p.size() == 3) fx = fy = p[0], cx = p[1], cy = p[2];
  else if (model == "PINHOLE" && p.size() == 4) fx = p[0], fy = p[1], cx = p[2], cy = p[3];
  else if (model == "SIMPLE_RADIAL" && p.size() == 4) fx = fy = p[0], cx = p[1], cy = p[2], k1 = p[3];
  else if (model == "RADIAL" && p.size() == 5) fx = fy = p[0], cx = p[1], cy = p[2], k1 = p[3], k2 = p[4];
  else if (model == "OPENCV" && p.size() == 8) fx = p[0], fy = p[1], cx = p[2], cy = p[3], k1 = p[4], k2 = p[5], p1 = p[6], p2 = p[7];
  else throw InputError("--known-distance: the lens model " + model + " is not one prepare can undistort points for (SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV)");
  // COLMAP's pixel centres lie at +0.5; a viewer's (column, row) names the pixel whose centre that is.
  const glm::dvec2 distorted((pixel.x + 0.5 - cx) / fx, (pixel.y + 0.5 - cy) / fy);
  // Invert COLMAP's distortion by Newton's method with a numerical Jacobian, as COLMAP does; a lens
  // too strong to invert there (a fisheye read as OPENCV) is refused rather than misread.
  const auto distort = [&](const glm::dvec2& v) {
    const double r2 = v.x * v.x + v.y * v.y, radial = 1 + k1 * r2 + k2 * r2 * r2;
    return v * radial + glm::dvec2(2 * p1 * v.x * v.y + p2 * (r2 + 2 * v.x * v.x), p1 * (r2 + 2 * v.y * v.y) + 2 * p2 * v.x * v.y);
  };
  glm::dvec2 u = distorted;
  for (int i = 0; i < 100; ++i) {
    const glm::dvec2 residual = distort(u) - distorted;
    if (glm::length(residual) < 1e-12) break;
    const double h = 1e-7 * std::max(1.0, glm::length(u));
    const glm::dvec2 dx = (distort(u + glm::dvec2(h, 0)) - distort(u - glm::dvec2(h, 0))) / (2 * h);
    const glm::dvec2 dy = (distort(u + glm::dvec2(0, h)) - distort(u - glm::dvec2(0, h))) / (2 * h);
    u -= glm::inverse(glm::dmat2(dx, dy)) * residual;
  }
  if (!std::isfinite(u.x) || !std::isfinite(u.y) || glm::length(distort(u) - distorted) > 1e-9)
    throw InputError("--known-distance: the lens COLMAP found (" + model + ") cannot be undone at pixel (" + std::to_string(pixel.x) + ", " +
                     std::to_string(pixel.y) + "); pick the point nearer the photo's centre");
  return u;
}

std::map<long long, Lens> read_colmap_cameras(const fs::path& cameras_txt) {
  std::map<long long, Lens> by_id;
  std::ifstream cameras(cameras_txt);
  for (std::string line; std::getline(cameras, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    long long id;
    Lens lens;
    if (!(words >> id >> lens.model >> lens.width >> lens.height)) continue;  // a blank or cut line
    for (double x; words >> x;) lens.params.push_back(x);
    by_id[id] = lens;
  }
  return by_id;
}

std::map<std::string, Lens> read_lenses(const fs::path& text_model) {
  const std::map<long long, Lens> by_id = read_colmap_cameras(text_model / "cameras.txt");
  std::ifstream images(text_model / "images.txt");
  std::map<std::string, Lens> lenses;
  bool pose_line = true;
  for (std::string line; std::getline(images, line);) {
    if (!line.empty() && line[0] == '#') continue;
    if (!pose_line) {
      pose_line = true;
      continue;
    }
    std::istringstream words(line);
    long long image_id, camera_id;
    double q[7];
    std::string name;
    if (!(words >> image_id >> q[0] >> q[1] >> q[2] >> q[3] >> q[4] >> q[5] >> q[6] >> camera_id >> name)) continue;
    pose_line = false;
    if (const auto lens = by_id.find(camera_id); lens != by_id.end()) lenses[name] = lens->second;
  }
  return lenses;
}

json scale_from_known_distance(const KnownDistance& known, const std::map<std::string, Lens>& lenses, const std::vector<io::Camera>& cameras,
                               const std::string& source) {
  json report = {{"cm", known.cm}, {"source", source}, {"points", json::array()}};
  std::vector<glm::dvec3> placed;
  for (std::size_t p = 0; p < known.points.size(); ++p) {
    struct Ray {
      std::string photo;
      const io::Camera* camera;
      glm::dvec3 origin, direction;
      glm::dvec2 undistorted;  // the pick in the undistorted pinhole camera
    };
    std::vector<Ray> rays;
    for (const auto& [photo, pixel] : known.points[p]) {
      const auto lens = lenses.find(photo);
      const auto camera = std::find_if(cameras.begin(), cameras.end(), [&](const io::Camera& c) { return c.image.filename() == photo; });
      if (lens == lenses.end() || camera == cameras.end())
        throw InputError(source + ": points[" + std::to_string(p) + "] names " + photo + ", which is not among the photos COLMAP placed (or whose pose was left out)");
      const glm::dvec2 n = lens->second.normalised(pixel);
      // The same ray through the undistorted pinhole camera.
      const glm::dvec2 undistorted(camera->cx + camera->fx * n.x, camera->cy + camera->fy * n.y);
      const glm::dvec3 origin = camera->centre();
      rays.push_back({photo, &*camera, origin, glm::normalize(camera->unproject(undistorted, 1.0) - origin), undistorted});
    }
    double widest = 0;
    for (const Ray& r : rays)
      for (const Ray& s : rays) widest = std::max(widest, std::acos(std::clamp(glm::dot(r.direction, s.direction), -1.0, 1.0)) * 180 / M_PI);
    const std::string at = source + ": points[" + std::to_string(p) + "]";
    if (widest < kMinRayAngleDeg)
      throw InputError(at + ": the photos that show it look at it from within " + std::to_string(widest).substr(0, 4) +
                       " degrees of each other; pick it in photos taken further apart");
    // The point nearest the rays (least squares: sum (I - d d^T) (X - o) = 0), leaving out `skip`,
    // and the rays' reprojection errors from it (judged in the undistorted cameras, whose focal
    // length is the original's).
    const auto triangulate = [&](std::size_t skip) {
      glm::dmat3 a(0.0);
      glm::dvec3 b(0.0);
      for (std::size_t i = 0; i < rays.size(); ++i) {
        if (i == skip) continue;
        const glm::dmat3 projector = glm::dmat3(1.0) - glm::outerProduct(rays[i].direction, rays[i].direction);
        a += projector, b += projector * rays[i].origin;
      }
      const glm::dvec3 x = glm::inverse(a) * b;
      std::vector<double> errors;
      for (const Ray& r : rays) {
        const glm::dvec3 projected = r.camera->project(x);
        errors.push_back(projected.z > 0 ? glm::length(glm::dvec2(projected) - r.undistorted) : 1e9);
      }
      return std::pair(x, errors);
    };
    const auto [x, errors] = triangulate(rays.size());
    if (*std::max_element(errors.begin(), errors.end()) > kMaxReprojectionPx) {
      // Which pick is wrong: the one whose removal leaves the others agreeing, when only one does
      // (two picks always agree when the error runs along their epipolar line, so two cannot tell).
      std::vector<std::string> culprits;
      for (std::size_t skip = 0; rays.size() >= 3 && skip < rays.size(); ++skip) {
        const auto [y, rest] = triangulate(skip);
        double worst_rest = 0;
        for (std::size_t i = 0; i < rest.size(); ++i)
          if (i != skip) worst_rest = std::max(worst_rest, rest[i]);
        if (worst_rest <= kMaxReprojectionPx) culprits.push_back(rays[skip].photo);
      }
      const std::string culprit = culprits.size() == 1 ? culprits.front() : "";
      std::string names;
      for (const Ray& r : rays) names += (names.empty() ? "" : ", ") + r.photo;
      const double worst = *std::max_element(errors.begin(), errors.end());
      throw InputError(at + (culprit.empty() ? ": the picks in " + names + " do not meet (" + (worst < 1e9 ? std::to_string(std::lround(worst)) + " px apart" : "behind a camera") +
                                                   "); check that each pick is the same point, or pick it in a third photo"
                                             : ": the pick in " + culprit + " is not where the other photos put the point; check that it is the same point"));
    }
    json error_by_photo = json::object();
    for (std::size_t i = 0; i < rays.size(); ++i) error_by_photo[rays[i].photo] = errors[i];
    placed.push_back(x);
    report["points"].push_back({{"reprojection_px", error_by_photo}, {"widest_ray_angle_deg", widest}});
  }
  const double units = glm::length(placed[1] - placed[0]);
  if (!(units > 0)) throw InputError(source + ": the two points are the same point");
  report["distance_units"] = units;
  report["cm_per_unit"] = known.cm / units;
  return report;
}

}  // namespace nf::prepare
