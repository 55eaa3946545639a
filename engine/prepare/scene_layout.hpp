#pragma once
// Where things are in a COLMAP reconstruction, found from the cameras and the sparse points alone:
// the point the cameras aim at (the animal's centre), their distance (the scene's scale in COLMAP's
// arbitrary unit), the floor (the plane most points near the animal lie on), which way is up (the
// floor's normal, or the cameras' mean up vector: most photos are taken upright), and which points
// are the animal (above the floor, near the centre) and which the background.
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/io/scene.hpp"
#include "engine/prepare/sparse_points.hpp"

namespace nf::prepare {

struct FloorPlane {
  glm::dvec3 point{0.0}, normal{0.0, 1.0, 0.0};  // the normal points to the cameras' side
  double height(const glm::dvec3& p) const { return glm::dot(p - point, normal); }
};

struct SceneLayout {
  glm::dvec3 focus{0.0};       // nearest every camera's viewing axis
  double reach = 1;            // the cameras' median distance from the focus
  FloorPlane floor;
  bool has_floor = false;      // enough points on one plane near the animal
  std::size_t floor_points = 0;
  glm::dvec3 up{0.0, 1.0, 0.0};   // the floor's normal when there is a floor, else the cameras' mean up
  double floor_tilt_deg = 0;      // between the floor's normal and the cameras' mean up
  std::vector<char> animal, background;  // per sparse point
  std::vector<glm::dvec3> animal_points;
  glm::dvec3 base() const { return has_floor ? focus - floor.height(focus) * floor.normal : focus; }  // the focus's foot on the floor
};

// InputError when the cameras' axes are all parallel (no point they aim at).
SceneLayout find_layout(const std::vector<io::Camera>& cameras, const SparsePoints& points);

// The animal's box in the floor's frame (u, v along the floor, n its normal; lo and hi about the
// focus's foot), generous: sparse points on fur are few and cluster on the body, while the head,
// tail and legs reach farther. Down to the floor (the paws stand on it).
struct AnimalBox {
  glm::dvec3 base{0.0}, u{1.0, 0.0, 0.0}, v{0.0, 0.0, 1.0}, n{0.0, 1.0, 0.0};
  glm::dvec3 lo{0.0}, hi{0.0};
  double horizontal = 0;  // the box's half width along the floor
  glm::dvec3 world(const glm::dvec3& local) const { return base + local.x * u + local.y * v + local.z * n; }
  glm::dvec3 local(const glm::dvec3& p) const { return {glm::dot(p - base, u), glm::dot(p - base, v), glm::dot(p - base, n)}; }
  std::vector<glm::dvec3> corners() const;
};
AnimalBox animal_box(const SceneLayout& layout);

// A camera COLMAP placed where no photo of the animal can have been taken: aimed well away from the
// point the others aim at, or several times nearer or further than the others (a photo matched to
// the wrong side of a symmetric animal or floor pattern). Such a pose would mislead every stage.
struct StrayCamera {
  std::size_t index;
  std::string reason;
};
std::vector<StrayCamera> stray_cameras(const std::vector<io::Camera>& cameras, const SceneLayout& layout);

// Frames of a video (in time order) that COLMAP placed off the path the camera took: the detour
// through a frame, |c - before| + |c - after| - |after - before|, above twice the median step
// between frames (a smooth path, hand-held too, detours by a small share of a step); the first and
// last frame when further than four steps from their one neighbour. Indices into `in_time_order`.
std::vector<StrayCamera> path_jumps(const std::vector<io::Camera>& in_time_order);

// The rigid transform that puts the scene upright in nf_gpu's convention: +y up, the origin on the
// floor under the animal's centre (at the centre when there is no floor). Lengths are kept.
glm::dmat4 upright_transform(const SceneLayout& layout);

}  // namespace nf::prepare
