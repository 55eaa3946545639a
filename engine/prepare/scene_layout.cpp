#include "engine/prepare/scene_layout.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "engine/core/error.hpp"

namespace nf::prepare {

namespace {

// The point nearest every camera's viewing axis (least squares): where the photographer aimed.
glm::dvec3 common_focus(const std::vector<io::Camera>& cameras) {
  glm::dmat3 a(0.0);
  glm::dvec3 b(0.0);
  for (const io::Camera& c : cameras) {
    const glm::dvec3 d = -glm::normalize(glm::dvec3(c.camera_to_world[2]));
    const glm::dmat3 across = glm::dmat3(1.0) - glm::outerProduct(d, d);
    a += across, b += across * c.centre();
  }
  if (std::abs(glm::determinant(a)) < 1e-12) throw InputError("prepare: the cameras' axes are parallel; the photos must be taken around the animal");
  return glm::inverse(a) * b;
}

// The plane most points lie on within `tolerance` (RANSAC, seeded: the same photos give the same
// floor), and its inlier count.
std::pair<FloorPlane, std::size_t> dominant_plane(const std::vector<glm::dvec3>& points, double tolerance) {
  FloorPlane best;
  std::size_t best_inliers = 0;
  if (points.size() < 3) return {best, 0};
  std::mt19937 rng(1);
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  for (int trial = 0; trial < 800; ++trial) {
    const glm::dvec3 a = points[pick(rng)], b = points[pick(rng)], c = points[pick(rng)];
    const glm::dvec3 n = glm::cross(b - a, c - a);
    if (glm::length(n) < 1e-12) continue;
    const FloorPlane p{a, glm::normalize(n)};
    std::size_t inliers = 0;
    for (const glm::dvec3& q : points) inliers += std::abs(p.height(q)) < tolerance;
    if (inliers > best_inliers) best = p, best_inliers = inliers;
  }
  return {best, best_inliers};
}

}  // namespace

SceneLayout find_layout(const std::vector<io::Camera>& cameras, const SparsePoints& points) {
  SceneLayout l;
  l.focus = common_focus(cameras);
  std::vector<double> distances;
  glm::dvec3 camera_mean(0.0), camera_up(0.0);
  for (const io::Camera& c : cameras) {
    distances.push_back(glm::distance(c.centre(), l.focus));
    camera_mean += c.centre();
    camera_up += glm::normalize(glm::dvec3(c.camera_to_world[1]));  // OpenGL: the camera's y is its up
  }
  camera_mean /= double(cameras.size());
  camera_up = glm::length(camera_up) > 0 ? glm::normalize(camera_up) : glm::dvec3(0, 1, 0);
  std::nth_element(distances.begin(), distances.begin() + std::ptrdiff_t(distances.size() / 2), distances.end());
  l.reach = distances[distances.size() / 2];

  // The floor: the dominant plane among the points within reach of the centre (a far wall is left out).
  std::vector<glm::dvec3> near;
  for (const glm::dvec3& p : points.positions)
    if (glm::distance(p, l.focus) < 1.5 * l.reach) near.push_back(p);
  const double tolerance = 0.005 * l.reach;
  std::tie(l.floor, l.floor_points) = dominant_plane(near, tolerance);
  l.has_floor = l.floor_points >= std::max<std::size_t>(30, near.size() / 10);
  if (l.floor.height(camera_mean) < 0) l.floor.normal = -l.floor.normal;
  l.up = l.has_floor ? l.floor.normal : camera_up;
  l.floor_tilt_deg = l.has_floor ? std::acos(std::clamp(glm::dot(l.floor.normal, camera_up), -1.0, 1.0)) * 180 / M_PI : 0;

  // Animal points stand above the floor, near the centre; floor points and far ones are background.
  l.animal.assign(points.positions.size(), 0);
  l.background.assign(points.positions.size(), 0);
  for (std::size_t i = 0; i < points.positions.size(); ++i) {
    const glm::dvec3& p = points.positions[i];
    const double h = l.has_floor ? l.floor.height(p) : 1.0, d = glm::distance(p, l.focus);
    if (h > 3 * tolerance && d < 0.6 * l.reach) l.animal[i] = 1, l.animal_points.push_back(p);
    else if (std::abs(h) < tolerance || d > 0.8 * l.reach || h < -3 * tolerance) l.background[i] = 1;
  }
  return l;
}

std::vector<StrayCamera> stray_cameras(const std::vector<io::Camera>& cameras, const SceneLayout& layout) {
  constexpr double kMaxOffAxisDeg = 35;  // the animal's centre beyond it lies at or outside a phone's frame
  constexpr double kMaxDistanceRatio = 3;
  std::vector<StrayCamera> strays;
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const io::Camera& c = cameras[i];
    const glm::dvec3 to_focus = layout.focus - c.centre(), axis = -glm::normalize(glm::dvec3(c.camera_to_world[2]));
    const double distance = glm::length(to_focus);
    const double off_axis = std::acos(std::clamp(glm::dot(to_focus, axis) / std::max(distance, 1e-300), -1.0, 1.0)) * 180 / M_PI;
    std::string reason;
    if (off_axis > kMaxOffAxisDeg) reason = "aimed " + std::to_string(std::lround(off_axis)) + " degrees away from the animal";
    else if (distance > kMaxDistanceRatio * layout.reach || distance * kMaxDistanceRatio < layout.reach)
      reason = "placed " + std::to_string(distance / layout.reach).substr(0, 4) + " times the other cameras' distance from the animal";
    if (!reason.empty()) strays.push_back({i, reason});
  }
  return strays;
}

std::vector<StrayCamera> path_jumps(const std::vector<io::Camera>& in_time_order) {
  const std::size_t n = in_time_order.size();
  std::vector<StrayCamera> jumps;
  if (n < 5) return jumps;
  const auto centre = [&](std::size_t i) { return in_time_order[i].centre(); };
  std::vector<double> steps;
  for (std::size_t i = 1; i < n; ++i) steps.push_back(glm::distance(centre(i), centre(i - 1)));
  std::nth_element(steps.begin(), steps.begin() + std::ptrdiff_t(steps.size() / 2), steps.end());
  const double step = steps[steps.size() / 2];
  if (!(step > 0)) return jumps;
  const auto describe = [&](double d) { return "off the video's path (a detour of " + std::to_string(d / step).substr(0, 4) + " steps between frames)"; };
  for (std::size_t i = 0; i < n; ++i) {
    double detour;
    if (i == 0 || i + 1 == n) {
      detour = glm::distance(centre(i), centre(i == 0 ? 1 : n - 2));
      if (detour > 4 * step) jumps.push_back({i, describe(detour)});
      continue;
    }
    detour = glm::distance(centre(i), centre(i - 1)) + glm::distance(centre(i), centre(i + 1)) - glm::distance(centre(i + 1), centre(i - 1));
    if (detour > 2 * step) jumps.push_back({i, describe(detour)});
  }
  return jumps;
}

std::vector<glm::dvec3> AnimalBox::corners() const {
  std::vector<glm::dvec3> out;
  for (int k = 0; k < 8; ++k) out.push_back(world({k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z}));
  return out;
}

AnimalBox animal_box(const SceneLayout& layout) {
  AnimalBox b;
  const glm::dvec3 n = layout.floor.normal;
  b.n = n, b.u = glm::normalize(glm::cross(n, std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0))), b.v = glm::cross(n, b.u);
  b.base = layout.base();
  double horizontal = 0, top = 0;
  for (const glm::dvec3& p : layout.animal_points) {
    const glm::dvec3 d = p - b.base;
    horizontal = std::max(horizontal, glm::length(d - glm::dot(d, n) * n));
    top = std::max(top, glm::dot(d, n));
  }
  b.horizontal = std::clamp(1.6 * horizontal, 0.3 * layout.reach, 0.6 * layout.reach);
  top = std::min(1.5 * top, 0.8 * layout.reach);
  b.lo = glm::dvec3(-b.horizontal, -b.horizontal, layout.has_floor ? 0.0 : -top), b.hi = glm::dvec3(b.horizontal, b.horizontal, top);
  return b;
}

glm::dmat4 upright_transform(const SceneLayout& l) {
  const glm::dvec3 y = glm::normalize(l.up);
  // Any heading will do; COLMAP's x axis laid on the floor keeps it recognisable.
  glm::dvec3 x = glm::dvec3(1, 0, 0) - y.x * y;
  if (glm::length(x) < 0.1) x = glm::dvec3(0, 0, 1) - y.z * y;
  x = glm::normalize(x);
  const glm::dvec3 z = glm::cross(x, y);
  glm::dmat3 rotation_to_scene = glm::transpose(glm::dmat3(x, y, z));  // rows x, y, z
  glm::dmat4 t(rotation_to_scene);
  t[3] = glm::dvec4(-(rotation_to_scene * l.base()), 1.0);
  return t;
}

}  // namespace nf::prepare
