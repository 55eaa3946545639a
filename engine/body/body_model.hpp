#pragma once
// A rigged, parametric quadruped body in the layout SMAL uses, so the procedural family of
// `quadruped.hpp` and a user's SMAL file load into the same structure:
//   shaped vertices  v(beta) = template + sum_s beta_s * shape_dirs[s]        (linear blend shapes)
//   shaped joints    J(beta) = joint_template + sum_s beta_s * joint_shape_dirs[s]
//   posed vertices   linear blend skinning with per-joint local rotations (axis-angle, rest frames
//                    aligned with the animal frame), then a similarity to the world.
// Coordinates are in the animal frame (as the paper's growth-direction prompt defines it): +x
// towards the animal's left, +y up, +z from tail to head.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/io/mesh.hpp"

namespace nf::body {

inline constexpr int kSkinInfluences = 4;

// Regions finer than the model's mesh: points on its triangles (a face and barycentric weights
// each) with their regions. The procedural family labels a finer build of itself this way, so a
// coarse template's small regions (eyes, inner ears, nose tip, pads) keep their size wherever a fit
// takes its triangles. Empty for SMAL files, whose regions are per vertex.
struct RegionDetail {
  std::vector<std::uint32_t> faces;     // N
  std::vector<float> barycentric;       // N x 3
  std::vector<std::int32_t> regions;    // N, ids of regions.hpp
  std::size_t size() const { return faces.size(); }
};

struct BodyModel {
  std::string name;
  std::vector<float> template_vertices;  // V x 3
  std::vector<std::uint32_t> triangles;  // F x 3
  std::vector<std::string> shape_names;  // S
  std::vector<float> shape_dirs;         // S x V x 3
  std::vector<std::string> joint_names;  // J
  std::vector<std::int32_t> parents;     // J; -1 for the root, parent index < own index
  std::vector<float> joint_template;     // J x 3
  std::vector<float> joint_shape_dirs;   // S x J x 3
  std::vector<std::uint32_t> skin_joints;  // V x 4
  std::vector<float> skin_weights;         // V x 4, each row sums to 1
  std::vector<std::int32_t> regions;       // V, ids of regions.hpp
  RegionDetail region_detail;              // optional

  std::size_t vertex_count() const { return template_vertices.size() / 3; }
  std::size_t joint_count() const { return joint_names.size(); }
  std::size_t shape_count() const { return shape_names.size(); }
  int joint_index(const std::string& name) const;  // -1 when absent
  int shape_index(const std::string& name) const;  // -1 when absent
  // Throws InputError naming `source` and the inconsistent field.
  void validate(const std::string& source) const;
};

struct BodyParams {
  std::vector<float> shape;                  // S (missing entries read as 0)
  std::vector<glm::vec3> joint_rotations;    // J axis-angle, local (missing entries: identity)
  glm::mat4 animal_to_world{1.0f};           // rigid part of the placement
  float scale = 1.0f;                        // uniform scale applied before animal_to_world
};

// The template's surface in the rest pose: its vertices, triangles and regions (no normals).
geometry::Mesh rest_mesh(const BodyModel& model);

// Joint positions after the shape blend (animal frame, rest pose).
std::vector<glm::vec3> shaped_joints(const BodyModel& model, const std::vector<float>& shape);
// Vertices after the shape blend (animal frame, rest pose), xyz.
std::vector<float> shaped_vertices(const BodyModel& model, const std::vector<float>& shape);
// Per-joint skinning matrices (rest -> posed, animal frame).
std::vector<glm::mat4> skinning_matrices(const BodyModel& model, const BodyParams& params);

// The posed body in world coordinates with area-weighted normals and the model's regions.
geometry::Mesh pose_body(const BodyModel& model, const BodyParams& params);
// The same in the animal frame (no world placement), for rules that need the animal's axes.
geometry::Mesh pose_body_animal_frame(const BodyModel& model, const BodyParams& params);

// Eye centres: the mean of each eye's region vertices on the posed body (an eye's side, +x left and
// -x right, taken in the rest pose), mapped to the world. Throws when a side has no eye vertices.
struct EyeCentres {
  glm::vec3 left, right;
  float distance() const { return glm::distance(left, right); }
};
EyeCentres eye_centres(const BodyModel& model, const BodyParams& params);

glm::mat4 rotation_from_axis_angle(const glm::vec3& axis_angle);

}  // namespace nf::body
