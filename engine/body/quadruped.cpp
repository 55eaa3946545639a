#include "engine/body/quadruped.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "engine/body/regions.hpp"
#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/marching_cubes.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/geometry/point_index.hpp"

namespace nf::body {

namespace {

constexpr float kDeg = 3.14159265358979f / 180.0f;

// Shape parameters: each scales bone offsets (length) or primitive radii (girth) of one part.
enum Shape : int {
  kTorsoLength, kTorsoGirth, kNeckLength, kNeckGirth, kHeadSize, kMuzzleLength, kMuzzleGirth,
  kEarLength, kEarWidth, kFrontLegLength, kRearLegLength, kLegGirth, kPawSize, kTailLength, kTailGirth, kShapeCount,
  kNoShape = -1,
};
const std::array<const char*, kShapeCount> kShapeNames = {
    "torso_length", "torso_girth", "neck_length", "neck_girth", "head_size", "muzzle_length", "muzzle_girth",
    "ear_length", "ear_width", "front_leg_length", "rear_leg_length", "leg_girth", "paw_size", "tail_length", "tail_girth"};

// Which part a primitive belongs to: drives the region rules.
enum class Part { torso, neck, head, muzzle, nose, ear, eye, leg_front, leg_rear, paw_front, paw_rear, tail };

struct Joint {
  std::string name;
  int parent;
  glm::vec3 position;  // rest, animal frame
  int length_shape;    // scales the offset from the parent
};

struct Primitive {
  Part part;
  bool ellipsoid;
  int joint_a, joint_b;                 // cone from a to b; ellipsoid centred at a
  glm::vec3 offset_a{0}, offset_b{0};   // added to the joints; scaled by offset_shape
  int offset_shape = kNoShape;
  float radius_a = 0, radius_b = 0;     // cone radii at a and b
  glm::vec3 radii{0};                   // ellipsoid radii
  float lateral_ratio = 1;              // cone cross-section: x radius / y radius (torso)
  glm::vec3 slab_normal{0};             // ears: a slab of constant thickness around the cone axis
  float slab_half = 0;
  int girth_shape = kNoShape;
  int drive_joint;
  float blend;                          // smooth-union radius (0: hard union)
};

struct Skeleton {
  std::vector<Joint> joints;
  std::vector<Primitive> primitives;
  glm::vec3 head{0}, tail_root{0};
  float tail_root_radius = 0;
};

int add_joint(Skeleton& s, const std::string& name, int parent, glm::vec3 p, int shape) {
  s.joints.push_back({name, parent, p, shape});
  return int(s.joints.size()) - 1;
}

Primitive cone(Part part, int a, int b, float ra, float rb, int girth, float blend, int drive = -1) {
  Primitive p{};
  p.part = part, p.ellipsoid = false, p.joint_a = a, p.joint_b = b, p.radius_a = ra, p.radius_b = rb;
  p.girth_shape = girth, p.drive_joint = drive < 0 ? a : drive, p.blend = blend;
  return p;
}

Primitive ellipsoid(Part part, int joint, glm::vec3 offset, int offset_shape, glm::vec3 radii, int girth, float blend) {
  Primitive p{};
  p.part = part, p.ellipsoid = true, p.joint_a = p.joint_b = joint, p.offset_a = p.offset_b = offset;
  p.offset_shape = offset_shape, p.radii = radii, p.girth_shape = girth, p.drive_joint = joint, p.blend = blend;
  return p;
}

// Where a ray from the centre of an axis-aligned ellipsoid leaves it.
float ellipsoid_exit(glm::vec3 dir, glm::vec3 radii) {
  const glm::vec3 q = dir / radii;
  return 1.0f / std::sqrt(glm::dot(q, q));
}

Skeleton make_skeleton(const QuadrupedProportions& p, float min_thickness) {
  Skeleton s;
  const float half = 0.5f * p.torso_length;
  const float h_front = p.front_leg_length, h_rear = p.rear_leg_length;
  const int pelvis = add_joint(s, "pelvis", -1, {0, h_rear, -half}, kNoShape);
  const int spine = add_joint(s, "spine", pelvis, {0, 0.5f * (h_front + h_rear), 0}, kTorsoLength);
  const int chest = add_joint(s, "chest", spine, {0, h_front, half}, kTorsoLength);
  const glm::vec3 chest_p = s.joints[chest].position;
  const int neck = add_joint(s, "neck", chest, chest_p + glm::vec3(0, 0.45f * p.chest_radius, 0.35f * p.chest_radius), kTorsoGirth);
  const float pitch = p.neck_pitch_deg * kDeg;
  const glm::vec3 head_p = s.joints[neck].position + p.neck_length * glm::vec3(0, std::sin(pitch), std::cos(pitch));
  const int head = add_joint(s, "head", neck, head_p, kNeckLength);
  s.head = head_p;
  const glm::vec3 head_radii = p.head_radius * glm::vec3(0.8f, 0.85f, 1.0f);
  const int muzzle = add_joint(s, "muzzle", head, head_p + p.head_radius * glm::vec3(0, -0.3f, 0.55f), kHeadSize);
  const int nose = add_joint(s, "nose", muzzle, s.joints[muzzle].position + glm::vec3(0, -0.1f * p.muzzle_radius, p.muzzle_length), kMuzzleLength);

  auto& prims = s.primitives;
  const float torso_blend = 0.5f * p.waist_radius;
  Primitive rear = cone(Part::torso, pelvis, spine, p.hip_radius, p.waist_radius, kTorsoGirth, torso_blend);
  Primitive front = cone(Part::torso, spine, chest, p.waist_radius, p.chest_radius, kTorsoGirth, torso_blend);
  rear.lateral_ratio = front.lateral_ratio = p.torso_width_ratio;
  prims.push_back(rear);
  prims.push_back(front);
  prims.push_back(cone(Part::neck, neck, head, 1.15f * p.neck_radius, 0.9f * p.neck_radius, kNeckGirth, 0.6f * p.neck_radius));
  prims.push_back(ellipsoid(Part::head, head, glm::vec3(0), kNoShape, head_radii, kHeadSize, 0.4f * p.head_radius));
  prims.push_back(cone(Part::muzzle, muzzle, nose, p.muzzle_radius, 0.8f * p.muzzle_radius, kMuzzleGirth, 0.6f * p.muzzle_radius));
  const float nose_radius = 0.42f * p.muzzle_radius;
  prims.push_back(ellipsoid(Part::nose, nose, glm::vec3(0, 0.15f * p.muzzle_radius, 0.55f * p.muzzle_radius), kMuzzleGirth,
                            glm::vec3(nose_radius), kMuzzleGirth, 0.3f * nose_radius));

  // Eyes: spheres sunk into the front of the head so that about a third of each shows.
  for (float side : {1.0f, -1.0f}) {
    const glm::vec3 dir = glm::normalize(glm::vec3(0.38f * side, 0.28f, 0.88f));
    const glm::vec3 offset = (ellipsoid_exit(dir, head_radii) - 0.3f * p.eye_radius) * dir;
    prims.push_back(ellipsoid(Part::eye, head, offset, kHeadSize, glm::vec3(p.eye_radius), kHeadSize, 0.0f));
  }
  // Ears: pointed slabs of constant thickness on top of the head; droop turns them out and down.
  const float ear_half = 0.5f * std::max(p.ear_thickness, min_thickness);
  for (float side : {1.0f, -1.0f}) {
    const glm::vec3 base_dir = glm::normalize(glm::vec3(0.55f * side, 0.8f, -0.1f));
    const glm::vec3 base = head_p + (ellipsoid_exit(base_dir, head_radii) - 0.25f * p.ear_width) * base_dir;
    const float droop = p.ear_droop_deg * kDeg, tilt = 20.0f * kDeg + droop;
    const glm::vec3 dir = glm::normalize(glm::vec3(side * std::sin(tilt), std::cos(tilt), -0.1f));
    const int ear = add_joint(s, side > 0 ? "ear_left" : "ear_right", head, base, kHeadSize);
    const int tip = add_joint(s, side > 0 ? "ear_left_tip" : "ear_right_tip", ear, base + p.ear_length * dir, kEarLength);
    Primitive e = cone(Part::ear, ear, tip, 0.5f * p.ear_width, 0.5f * p.ear_width * p.ear_tip_ratio, kEarWidth, 0.3f * p.ear_width);
    const glm::vec3 forward(0, 0, 1);
    e.slab_normal = glm::normalize(forward - glm::dot(forward, dir) * dir);
    e.slab_half = ear_half;
    prims.push_back(e);
  }
  // Legs: shoulder/hip inside the torso, a bent joint half way, the paw on the ground (y = 0).
  const float paw_joint_y = 0.9f * p.paw_radius;
  for (int rear_leg = 0; rear_leg < 2; ++rear_leg) {
    for (float side : {1.0f, -1.0f}) {
      const bool is_rear = rear_leg == 1;
      const float radius = is_rear ? p.hip_radius : p.chest_radius;
      const float top_y = is_rear ? h_rear : h_front;
      const glm::vec3 top(side * 0.45f * radius * p.torso_width_ratio, top_y - 0.15f * radius,
                          is_rear ? -half + 0.1f * radius : half - 0.2f * radius);
      const float drop = top.y - paw_joint_y;
      const glm::vec3 mid = top + glm::vec3(0, -0.5f * drop, (is_rear ? 0.12f : -0.05f) * drop);
      const glm::vec3 low(top.x, paw_joint_y, top.z + (is_rear ? -0.06f : 0.02f) * drop);
      const std::string sfx = side > 0 ? "_left" : "_right";
      const int parent = is_rear ? pelvis : chest;
      const int j0 = add_joint(s, (is_rear ? "hip" : "shoulder") + sfx, parent, top, kTorsoGirth);
      // Front and rear legs each their own length: animals differ in how they stand (a hyena's
      // sloping back, a rabbit's long hind legs), and one shared length cost the paws' labels.
      const int length_shape = is_rear ? kRearLegLength : kFrontLegLength;
      const int j1 = add_joint(s, (is_rear ? "knee" : "elbow") + sfx, j0, mid, length_shape);
      const int j2 = add_joint(s, (is_rear ? "ankle" : "wrist") + sfx, j1, low, length_shape);
      const Part leg = is_rear ? Part::leg_rear : Part::leg_front;
      const float r_mid = 0.5f * (p.leg_radius_top + p.leg_radius_bottom);
      prims.push_back(cone(leg, j0, j1, p.leg_radius_top, r_mid, kLegGirth, 0.6f * p.leg_radius_top));
      prims.push_back(cone(leg, j1, j2, r_mid, p.leg_radius_bottom, kLegGirth, 0.5f * p.leg_radius_bottom));
      prims.push_back(ellipsoid(is_rear ? Part::paw_rear : Part::paw_front, j2, p.paw_radius * glm::vec3(0, -0.35f, 0.35f),
                                kPawSize, p.paw_radius * glm::vec3(0.85f, 0.55f, 1.2f), kPawSize, 0.6f * p.leg_radius_bottom));
    }
  }
  // Tail: four segments from the rump, pitched and curling upwards.
  glm::vec3 at = s.joints[pelvis].position + glm::vec3(0, 0.35f * p.hip_radius, -0.8f * p.hip_radius);
  s.tail_root = at, s.tail_root_radius = p.tail_radius_base;
  int prev = add_joint(s, "tail_0", pelvis, at, kTorsoGirth);
  const int segments = 4;
  for (int k = 0; k < segments; ++k) {
    const float angle = (p.tail_pitch_deg + p.tail_curl_deg * (k + 0.5f) / segments) * kDeg;
    at += (p.tail_length / segments) * glm::vec3(0, std::sin(angle), -std::cos(angle));
    const int next = add_joint(s, "tail_" + std::to_string(k + 1), prev, at, kTailLength);
    const float ra = p.tail_radius_base + (p.tail_radius_tip - p.tail_radius_base) * k / segments;
    const float rb = p.tail_radius_base + (p.tail_radius_tip - p.tail_radius_base) * (k + 1) / segments;
    prims.push_back(cone(Part::tail, prev, next, ra, rb, kTailGirth, k == 0 ? 0.8f * p.tail_radius_base : 0.3f * rb));
    prev = next;
  }
  return s;
}

// Joint positions under a shape vector (linear in it: each offset scales by 1 + beta).
std::vector<glm::vec3> joints_for(const Skeleton& s, const std::array<float, kShapeCount>& beta) {
  std::vector<glm::vec3> out(s.joints.size());
  for (std::size_t k = 0; k < s.joints.size(); ++k) {
    const Joint& j = s.joints[k];
    if (j.parent < 0) { out[k] = j.position; continue; }
    const float scale = 1.0f + (j.length_shape == kNoShape ? 0.0f : beta[j.length_shape]);
    out[k] = out[j.parent] + scale * (j.position - s.joints[j.parent].position);
  }
  return out;
}

struct Ends { glm::vec3 a, b; };
Ends ends_for(const Primitive& p, const std::vector<glm::vec3>& joints, const std::array<float, kShapeCount>& beta) {
  const float scale = 1.0f + (p.offset_shape == kNoShape ? 0.0f : beta[p.offset_shape]);
  return {joints[p.joint_a] + scale * p.offset_a, joints[p.joint_b] + scale * p.offset_b};
}

// Signed distance (approximate away from the surface) and local coordinates of a point.
struct Local { float distance, t; glm::vec3 radial; };
Local evaluate(const Primitive& p, const Ends& e, glm::vec3 x) {
  if (p.ellipsoid) {
    const glm::vec3 q = x - e.a;
    const float k0 = glm::length(q / p.radii), k1 = glm::length(q / (p.radii * p.radii));
    const float d = k1 > 0 ? k0 * (k0 - 1.0f) / k1 : -std::min({p.radii.x, p.radii.y, p.radii.z});
    return {d, 0.0f, q};
  }
  const glm::vec3 ab = e.b - e.a;
  const float t = std::clamp(glm::dot(x - e.a, ab) / std::max(glm::dot(ab, ab), 1e-20f), 0.0f, 1.0f);
  const glm::vec3 radial = x - (e.a + t * ab);
  glm::vec3 o = radial;
  o.x /= p.lateral_ratio;
  float d = (glm::length(o) - (p.radius_a + t * (p.radius_b - p.radius_a))) * std::min(1.0f, p.lateral_ratio);
  if (p.slab_half > 0) d = std::max(d, std::fabs(glm::dot(x - e.a, p.slab_normal)) - p.slab_half);
  return {d, t, radial};
}

float smooth_min(float a, float b, float k) {
  if (k <= 0) return std::min(a, b);
  const float h = std::max(k - std::fabs(a - b), 0.0f) / k;
  return std::min(a, b) - 0.25f * h * h * k;
}

geometry::Mesh extract_surface(const Skeleton& s, float voxel) {
  const std::array<float, kShapeCount> zero{};
  const std::vector<glm::vec3> joints = joints_for(s, zero);
  std::vector<Ends> ends;
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (const Primitive& p : s.primitives) {
    ends.push_back(ends_for(p, joints, zero));
    const float r = p.ellipsoid ? std::max({p.radii.x, p.radii.y, p.radii.z}) : std::max(p.radius_a, p.radius_b);
    lo = glm::min(lo, glm::min(ends.back().a, ends.back().b) - r);
    hi = glm::max(hi, glm::max(ends.back().a, ends.back().b) + r);
  }
  lo -= 3.0f * voxel, hi += 3.0f * voxel;
  const glm::ivec3 dims = glm::ivec3(glm::ceil((hi - lo) / voxel)) + 1;
  std::vector<float> field(std::size_t(dims.x) * dims.y * dims.z);
  parallel_for(std::size_t(dims.z), [&](std::size_t z0, std::size_t z1) {
    for (std::size_t z = z0; z < z1; ++z)
      for (int y = 0; y < dims.y; ++y)
        for (int x = 0; x < dims.x; ++x) {
          const glm::vec3 at = lo + voxel * glm::vec3(x, y, float(z));
          float d = 1e30f;
          for (std::size_t k = 0; k < s.primitives.size(); ++k)
            d = smooth_min(d, evaluate(s.primitives[k], ends[k], at).distance, s.primitives[k].blend);
          field[(z * dims.y + y) * dims.x + x] = d;
        }
  }, 1);
  geometry::Mesh mesh = geometry::marching_cubes(field.data(), dims, lo, glm::vec3(voxel), 0.0f);
  geometry::keep_largest_component(mesh);
  return mesh;
}

// The rules that turn the nearest part into one of the method's regions (regions.hpp).
Region region_rule(const QuadrupedProportions& p, const Skeleton& s, const Primitive& prim, glm::vec3 v, glm::vec3 n) {
  const glm::vec3 head = s.head;
  const bool near_tail_root = glm::distance(v, s.tail_root) < 2.2f * s.tail_root_radius && v.y < s.tail_root.y + 0.2f * s.tail_root_radius;
  switch (prim.part) {
    case Part::eye: return Region::eyes;
    case Part::nose: return n.z > -0.3f ? Region::nosetip : Region::face;
    case Part::muzzle: return Region::face;
    case Part::head: return p.mane && v.z < head.z - 0.15f * p.head_radius ? Region::mane : Region::face;
    case Part::ear: return glm::dot(n, prim.slab_normal) > 0.5f ? Region::inner_earcanal : Region::ears;
    case Part::neck: return p.mane ? Region::mane : Region::neck;
    case Part::leg_front: return Region::leg_front;
    case Part::leg_rear: return Region::leg_rear;
    case Part::paw_front: return n.y < -float(kPadFacing) ? Region::paw_pads : Region::front_paws;
    case Part::paw_rear: return n.y < -float(kPadFacing) ? Region::paw_pads : Region::paws;
    case Part::tail: return near_tail_root ? Region::under_tail : Region::tail;
    case Part::torso:
      if (near_tail_root) return Region::under_tail;
      if (n.y < -0.55f) return Region::belly;
      return Region::body;
  }
  return Region::body;
}

}  // namespace

const std::vector<std::string>& known_animals() {
  static const std::vector<std::string> names = {"cat", "dog", "fox", "panda", "tiger", "lion"};
  return names;
}

QuadrupedProportions animal_proportions(const std::string& animal) {
  QuadrupedProportions p;  // the defaults are a domestic cat
  p.animal = animal;
  if (animal == "cat") return p;
  if (animal == "dog") {  // beagle
    p.torso_length = 0.36f, p.chest_radius = 0.115f, p.waist_radius = 0.085f, p.hip_radius = 0.095f, p.torso_width_ratio = 0.75f;
    p.front_leg_length = 0.30f, p.rear_leg_length = 0.32f, p.leg_radius_top = 0.045f, p.leg_radius_bottom = 0.022f, p.paw_radius = 0.03f;
    p.neck_length = 0.12f, p.neck_radius = 0.055f, p.neck_pitch_deg = 45;
    p.head_radius = 0.065f, p.muzzle_length = 0.085f, p.muzzle_radius = 0.034f;
    p.ear_length = 0.11f, p.ear_width = 0.07f, p.ear_thickness = 0.006f, p.ear_tip_ratio = 0.7f, p.ear_droop_deg = 140;
    p.eye_radius = 0.014f, p.tail_length = 0.28f, p.tail_radius_base = 0.024f, p.tail_radius_tip = 0.012f;
    p.tail_pitch_deg = 45, p.tail_curl_deg = 30;
    return p;
  }
  if (animal == "fox") {
    p.torso_length = 0.38f, p.chest_radius = 0.095f, p.waist_radius = 0.075f, p.hip_radius = 0.085f, p.torso_width_ratio = 0.75f;
    p.front_leg_length = 0.30f, p.rear_leg_length = 0.32f, p.leg_radius_top = 0.035f, p.leg_radius_bottom = 0.016f, p.paw_radius = 0.024f;
    p.neck_length = 0.11f, p.neck_radius = 0.048f, p.neck_pitch_deg = 40;
    p.head_radius = 0.058f, p.muzzle_length = 0.08f, p.muzzle_radius = 0.024f;
    p.ear_length = 0.08f, p.ear_width = 0.06f, p.ear_thickness = 0.005f, p.ear_tip_ratio = 0.12f;
    p.eye_radius = 0.012f, p.tail_length = 0.40f, p.tail_radius_base = 0.035f, p.tail_radius_tip = 0.03f;
    p.tail_pitch_deg = -25, p.tail_curl_deg = 25;
    return p;
  }
  if (animal == "panda") {
    p.torso_length = 0.80f, p.chest_radius = 0.30f, p.waist_radius = 0.27f, p.hip_radius = 0.28f, p.torso_width_ratio = 0.9f;
    p.front_leg_length = 0.50f, p.rear_leg_length = 0.48f, p.leg_radius_top = 0.12f, p.leg_radius_bottom = 0.085f, p.paw_radius = 0.10f;
    p.neck_length = 0.14f, p.neck_radius = 0.20f, p.neck_pitch_deg = 20;
    p.head_radius = 0.20f, p.muzzle_length = 0.09f, p.muzzle_radius = 0.075f;
    p.ear_length = 0.09f, p.ear_width = 0.11f, p.ear_thickness = 0.02f, p.ear_tip_ratio = 0.75f;
    p.eye_radius = 0.022f, p.tail_length = 0.14f, p.tail_radius_base = 0.05f, p.tail_radius_tip = 0.035f;
    p.tail_pitch_deg = -35, p.tail_curl_deg = 10;
    return p;
  }
  if (animal == "tiger" || animal == "lion") {
    p.torso_length = 1.05f, p.chest_radius = 0.27f, p.waist_radius = 0.20f, p.hip_radius = 0.22f, p.torso_width_ratio = 0.72f;
    p.front_leg_length = 0.80f, p.rear_leg_length = 0.84f, p.leg_radius_top = 0.10f, p.leg_radius_bottom = 0.06f, p.paw_radius = 0.08f;
    p.neck_length = 0.24f, p.neck_radius = 0.15f, p.neck_pitch_deg = 25;
    p.head_radius = 0.17f, p.muzzle_length = 0.10f, p.muzzle_radius = 0.08f;
    p.ear_length = 0.08f, p.ear_width = 0.09f, p.ear_thickness = 0.015f, p.ear_tip_ratio = 0.6f;
    p.eye_radius = 0.024f, p.tail_length = 0.90f, p.tail_radius_base = 0.05f, p.tail_radius_tip = 0.03f;
    p.tail_pitch_deg = -45, p.tail_curl_deg = 45;
    // Both grow a mane in their knowledge (a lion's mane, a tiger's ruff), so their bodies carry its
    // region: the truth then says where the knowledge's mane length grew.
    p.mane = true;
    if (animal == "lion") p.head_radius = 0.18f, p.tail_radius_tip = 0.035f;
    return p;
  }
  std::string names;
  for (const auto& a : known_animals()) names += (names.empty() ? "" : ", ") + a;
  throw UsageError("unknown animal '" + animal + "'; known animals: " + names);
}

QuadrupedProportions vary_proportions(const QuadrupedProportions& p, unsigned seed, float amount) {
  QuadrupedProportions out = p;
  std::mt19937 rng(seed * 2654435761u + 17u);
  std::uniform_real_distribution<float> u(1.0f - amount, 1.0f + amount);
  for (float* f : {&out.torso_length, &out.chest_radius, &out.waist_radius, &out.hip_radius, &out.front_leg_length,
                   &out.rear_leg_length, &out.leg_radius_top, &out.leg_radius_bottom, &out.paw_radius, &out.neck_length,
                   &out.neck_radius, &out.head_radius, &out.muzzle_length, &out.muzzle_radius, &out.ear_length,
                   &out.ear_width, &out.eye_radius, &out.tail_length, &out.tail_radius_base, &out.tail_radius_tip})
    *f *= u(rng);
  // The pitches swing +-20 and +-40 degrees at the default spread, less below it and up to half
  // as much again above it (a wider family, not a broken one).
  const float swing = std::min(1.5f, amount / kDefaultProportionSpread);  // exactly 1 at the default
  const float neck = u(rng), tail = u(rng);
  if (amount > 0) {
    out.neck_pitch_deg += 20.0f * (neck - 1.0f) / amount * swing;
    out.tail_pitch_deg += 40.0f * (tail - 1.0f) / amount * swing;
  }
  // The head's parts keep to the head: drawn apart they could make a neck wider than the head that
  // swallows the eyes. Their ratios to the head stay within 13 % of the family's, which the default
  // amount never reaches (1.06 / 0.94), so only a wider spread is held by it; there the neck is
  // also no wider against the head than the family's (a panda's neck is already as wide as its
  // head). So the neck's bound steps from 1.13 to 1 just above the default: default scenes stay
  // exactly what they were, and a wider family never thickens the neck against the head.
  const float head = out.head_radius / p.head_radius;
  for (auto member : {&QuadrupedProportions::neck_radius, &QuadrupedProportions::muzzle_length, &QuadrupedProportions::muzzle_radius,
                      &QuadrupedProportions::ear_length, &QuadrupedProportions::ear_width, &QuadrupedProportions::eye_radius}) {
    const float highest = member == &QuadrupedProportions::neck_radius && amount > kDefaultProportionSpread ? 1.0f : 1.13f;
    if (const float ratio = out.*member / p.*member / head; ratio < 1.0f / 1.13f || ratio > highest)
      out.*member = p.*member * head * std::clamp(ratio, 1.0f / 1.13f, highest);
  }
  out.rear_leg_length = std::max(out.rear_leg_length, 0.9f * out.front_leg_length);
  return out;
}

BodyModel build_quadruped(const QuadrupedProportions& p, const QuadrupedBuildOptions& options) {
  const float voxel = options.voxel > 0 ? options.voxel : p.torso_length / 110.0f;
  const Skeleton s = make_skeleton(p, options.min_thickness > 0 ? options.min_thickness : 2.5f * voxel);
  const geometry::Mesh mesh = extract_surface(s, voxel);
  if (mesh.vertex_count() == 0) throw InternalError("quadruped '" + p.animal + "': the body surface is empty");

  BodyModel model;
  model.name = "quadruped:" + p.animal;
  model.template_vertices = mesh.positions;
  model.triangles = mesh.triangles;
  const std::size_t nv = mesh.vertex_count(), nj = s.joints.size(), np = s.primitives.size();
  for (const Joint& j : s.joints) {
    model.joint_names.push_back(j.name);
    model.parents.push_back(j.parent);
    model.joint_template.insert(model.joint_template.end(), {j.position.x, j.position.y, j.position.z});
  }
  for (const char* name : kShapeNames) model.shape_names.push_back(name);

  // Per vertex: the four primitives with the largest soft weights and their local coordinates.
  struct Influence { int primitive; float weight, t; glm::vec3 radial; };
  std::vector<std::array<Influence, 4>> influences(nv);
  model.regions.resize(nv);
  const std::array<float, kShapeCount> zero{};
  const std::vector<glm::vec3> rest_joints = joints_for(s, zero);
  std::vector<Ends> rest_ends;
  for (const Primitive& prim : s.primitives) rest_ends.push_back(ends_for(prim, rest_joints, zero));
  const float temperature = 0.015f * p.torso_length;
  parallel_for(nv, [&](std::size_t v0, std::size_t v1) {
    std::vector<Local> local(np);
    for (std::size_t i = v0; i < v1; ++i) {
      const glm::vec3 v(mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]);
      const glm::vec3 n(mesh.normals[3 * i], mesh.normals[3 * i + 1], mesh.normals[3 * i + 2]);
      std::size_t nearest = 0;
      for (std::size_t k = 0; k < np; ++k) {
        local[k] = evaluate(s.primitives[k], rest_ends[k], v);
        if (local[k].distance < local[nearest].distance) nearest = k;
      }
      model.regions[i] = region_id(region_rule(p, s, s.primitives[nearest], v, n));
      std::array<Influence, 4> best{};
      for (auto& b : best) b = {-1, -1.0f, 0, glm::vec3(0)};
      for (std::size_t k = 0; k < np; ++k) {
        const float w = std::exp(-(local[k].distance - local[nearest].distance) / temperature);
        if (w <= best[3].weight) continue;
        best[3] = {int(k), w, local[k].t, local[k].radial};
        std::sort(best.begin(), best.end(), [](const Influence& a, const Influence& b) { return a.weight > b.weight; });
      }
      float total = 0;
      for (const auto& b : best) total += std::max(b.weight, 0.0f);
      for (auto& b : best) b.weight = b.primitive < 0 ? 0.0f : b.weight / total;
      influences[i] = best;
    }
  });

  // Skinning: primitive weights summed per driving joint.
  model.skin_joints.assign(nv * kSkinInfluences, 0);
  model.skin_weights.assign(nv * kSkinInfluences, 0.0f);
  for (std::size_t i = 0; i < nv; ++i) {
    std::array<std::pair<int, float>, 4> joint_w{};
    int used = 0;
    for (const auto& b : influences[i]) {
      if (b.primitive < 0 || b.weight <= 0) continue;
      const int j = s.primitives[b.primitive].drive_joint;
      int slot = 0;
      while (slot < used && joint_w[slot].first != j) ++slot;
      if (slot == used) joint_w[used++] = {j, 0.0f};
      joint_w[slot].second += b.weight;
    }
    for (int k = 0; k < used; ++k) model.skin_joints[i * 4 + k] = std::uint32_t(joint_w[k].first), model.skin_weights[i * 4 + k] = joint_w[k].second;
  }

  // Blend shapes: the deformation is linear in beta, so beta = e_s minus beta = 0 is exact.
  auto deform = [&](const std::array<float, kShapeCount>& beta, std::vector<float>& verts, std::vector<glm::vec3>& joints) {
    joints = joints_for(s, beta);
    std::vector<Ends> e;
    for (const Primitive& prim : s.primitives) e.push_back(ends_for(prim, joints, beta));
    verts.assign(nv * 3, 0.0f);
    for (std::size_t i = 0; i < nv; ++i) {
      glm::vec3 v(0);
      for (const auto& b : influences[i]) {
        if (b.primitive < 0) continue;
        const Primitive& prim = s.primitives[b.primitive];
        const float girth = 1.0f + (prim.girth_shape == kNoShape ? 0.0f : beta[prim.girth_shape]);
        const glm::vec3 axis = e[b.primitive].a + b.t * (e[b.primitive].b - e[b.primitive].a);
        v += b.weight * (axis + girth * b.radial);
      }
      verts[3 * i] = v.x, verts[3 * i + 1] = v.y, verts[3 * i + 2] = v.z;
    }
  };
  std::vector<float> base_v;
  std::vector<glm::vec3> base_j;
  deform(zero, base_v, base_j);
  model.template_vertices = base_v;  // equals the surface up to rounding; keeps v(0) exact
  model.shape_dirs.resize(kShapeCount * nv * 3);
  model.joint_shape_dirs.resize(kShapeCount * nj * 3);
  for (int sh = 0; sh < kShapeCount; ++sh) {
    std::array<float, kShapeCount> beta{};
    beta[sh] = 1.0f;
    std::vector<float> v;
    std::vector<glm::vec3> j;
    deform(beta, v, j);
    for (std::size_t i = 0; i < nv * 3; ++i) model.shape_dirs[sh * nv * 3 + i] = v[i] - base_v[i];
    for (std::size_t k = 0; k < nj; ++k)
      for (int c = 0; c < 3; ++c) model.joint_shape_dirs[(sh * nj + k) * 3 + c] = j[k][c] - base_j[k][c];
  }
  model.validate(model.name);
  return model;
}

BodyParams random_pose(const BodyModel& model, unsigned seed) {
  BodyParams params;
  params.joint_rotations.assign(model.joint_count(), glm::vec3(0));
  if (seed == 0) return params;
  std::mt19937 rng(seed * 747796405u + 2891336453u);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  auto set = [&](const std::string& joint, glm::vec3 aa) {
    const int j = model.joint_index(joint);
    if (j >= 0) params.joint_rotations[size_t(j)] = aa;
  };
  set("neck", glm::vec3(0.08f * u(rng), 0.15f * u(rng), 0));
  set("head", glm::vec3(0.1f * u(rng), 0.2f * u(rng), 0.05f * u(rng)));
  for (int k = 0; k < 4; ++k) set("tail_" + std::to_string(k), glm::vec3(0.1f * u(rng), 0.25f * u(rng), 0));
  for (const char* leg : {"shoulder_left", "shoulder_right", "hip_left", "hip_right"}) set(leg, glm::vec3(0.12f * u(rng), 0, 0));
  return params;
}

}  // namespace nf::body
