#include "engine/body/body_model.hpp"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/body/regions.hpp"
#include "engine/core/error.hpp"
#include "engine/geometry/mesh_tools.hpp"

namespace nf::body {

int BodyModel::joint_index(const std::string& joint) const {
  for (std::size_t j = 0; j < joint_names.size(); ++j)
    if (joint_names[j] == joint) return int(j);
  return -1;
}

int BodyModel::shape_index(const std::string& shape) const {
  for (std::size_t s = 0; s < shape_names.size(); ++s)
    if (shape_names[s] == shape) return int(s);
  return -1;
}

void BodyModel::validate(const std::string& source) const {
  const std::size_t v = vertex_count(), j = joint_count(), s = shape_count();
  auto fail = [&](const std::string& what) { throw InputError(source + ": " + what); };
  if (template_vertices.size() % 3 != 0 || v == 0) fail("template_vertices must hold xyz for at least one vertex");
  if (triangles.size() % 3 != 0) fail("triangles must hold vertex index triples");
  for (std::uint32_t i : triangles)
    if (i >= v) fail("triangles: vertex index " + std::to_string(i) + " >= vertex count " + std::to_string(v));
  if (shape_dirs.size() != s * v * 3) fail("shape_dirs: expected shapes x vertices x 3 = " + std::to_string(s * v * 3) + " values");
  if (j == 0 || parents.size() != j || joint_template.size() != j * 3) fail("joints: names, parents and joint_template disagree in count");
  if (joint_shape_dirs.size() != s * j * 3) fail("joint_shape_dirs: expected shapes x joints x 3 values");
  for (std::size_t k = 0; k < j; ++k)
    if (parents[k] >= int(k) || (parents[k] < 0 && k != 0)) fail("parents[" + std::to_string(k) + "] must name an earlier joint (root first)");
  if (skin_joints.size() != v * kSkinInfluences || skin_weights.size() != v * kSkinInfluences)
    fail("skin_joints / skin_weights: expected 4 influences per vertex");
  for (std::size_t i = 0; i < v; ++i) {
    float sum = 0;
    for (int k = 0; k < kSkinInfluences; ++k) {
      if (skin_joints[i * 4 + k] >= j) fail("skin_joints: joint index out of range at vertex " + std::to_string(i));
      const float w = skin_weights[i * 4 + k];
      if (!(w >= 0.0f) || !std::isfinite(w)) fail("skin_weights: negative or non-finite weight at vertex " + std::to_string(i));
      sum += w;
    }
    if (std::fabs(sum - 1.0f) > 1e-3f) fail("skin_weights: weights of vertex " + std::to_string(i) + " sum to " + std::to_string(sum));
  }
  if (!regions.empty() && regions.size() != v) fail("regions: expected one per vertex");
  for (std::int32_t r : regions) region_name(r, source + ": regions");
  const RegionDetail& d = region_detail;
  if (d.barycentric.size() != 3 * d.size() || d.regions.size() != d.size())
    fail("region_detail: expected a face, three barycentric weights and a region per point");
  for (std::uint32_t f : d.faces)
    if (f >= triangles.size() / 3) fail("region_detail: face " + std::to_string(f) + " >= face count " + std::to_string(triangles.size() / 3));
  for (std::int32_t r : d.regions) region_name(r, source + ": region_detail");
  for (float x : template_vertices)
    if (!std::isfinite(x)) fail("template_vertices: NaN or Inf coordinate");
}

geometry::Mesh rest_mesh(const BodyModel& model) {
  geometry::Mesh mesh;
  mesh.positions = model.template_vertices;
  mesh.triangles = model.triangles;
  mesh.regions = model.regions;
  return mesh;
}

namespace {

float shape_value(const std::vector<float>& shape, std::size_t s) { return s < shape.size() ? shape[s] : 0.0f; }

}  // namespace

std::vector<glm::vec3> shaped_joints(const BodyModel& model, const std::vector<float>& shape) {
  const std::size_t j = model.joint_count();
  std::vector<glm::vec3> out(j);
  for (std::size_t k = 0; k < j; ++k) {
    glm::vec3 p(model.joint_template[3 * k], model.joint_template[3 * k + 1], model.joint_template[3 * k + 2]);
    for (std::size_t s = 0; s < model.shape_count(); ++s) {
      const float b = shape_value(shape, s);
      if (b == 0.0f) continue;
      const float* d = &model.joint_shape_dirs[(s * j + k) * 3];
      p += b * glm::vec3(d[0], d[1], d[2]);
    }
    out[k] = p;
  }
  return out;
}

std::vector<float> shaped_vertices(const BodyModel& model, const std::vector<float>& shape) {
  std::vector<float> v = model.template_vertices;
  const std::size_t n = v.size();
  for (std::size_t s = 0; s < model.shape_count(); ++s) {
    const float b = shape_value(shape, s);
    if (b == 0.0f) continue;
    const float* d = &model.shape_dirs[s * n];
    for (std::size_t i = 0; i < n; ++i) v[i] += b * d[i];
  }
  return v;
}

glm::mat4 rotation_from_axis_angle(const glm::vec3& aa) {
  const float angle = glm::length(aa);
  if (angle < 1e-12f) return glm::mat4(1.0f);
  return glm::rotate(glm::mat4(1.0f), angle, aa / angle);
}

std::vector<glm::mat4> skinning_matrices(const BodyModel& model, const BodyParams& params) {
  const std::vector<glm::vec3> joints = shaped_joints(model, params.shape);
  const std::size_t j = joints.size();
  std::vector<glm::mat4> global(j), skin(j);
  for (std::size_t k = 0; k < j; ++k) {
    const glm::mat4 r = k < params.joint_rotations.size() ? rotation_from_axis_angle(params.joint_rotations[k]) : glm::mat4(1.0f);
    const int parent = model.parents[k];
    const glm::vec3 offset = parent < 0 ? joints[k] : joints[k] - joints[parent];
    const glm::mat4 local = glm::translate(glm::mat4(1.0f), offset) * r;
    global[k] = parent < 0 ? local : global[parent] * local;
    skin[k] = global[k] * glm::translate(glm::mat4(1.0f), -joints[k]);
  }
  return skin;
}

geometry::Mesh pose_body_animal_frame(const BodyModel& model, const BodyParams& params) {
  const std::vector<float> rest = shaped_vertices(model, params.shape);
  const std::vector<glm::mat4> skin = skinning_matrices(model, params);
  geometry::Mesh mesh;
  mesh.positions.resize(rest.size());
  for (std::size_t i = 0; i < model.vertex_count(); ++i) {
    glm::mat4 m(0.0f);
    for (int k = 0; k < kSkinInfluences; ++k) m += model.skin_weights[i * 4 + k] * skin[model.skin_joints[i * 4 + k]];
    const glm::vec4 p = m * glm::vec4(rest[3 * i], rest[3 * i + 1], rest[3 * i + 2], 1.0f);
    for (int c = 0; c < 3; ++c) mesh.positions[3 * i + c] = p[c];
  }
  mesh.triangles = model.triangles;
  mesh.regions = model.regions;
  geometry::compute_vertex_normals(mesh);
  return mesh;
}

geometry::Mesh pose_body(const BodyModel& model, const BodyParams& params) {
  geometry::Mesh mesh = pose_body_animal_frame(model, params);
  const glm::mat4 place = params.animal_to_world * glm::scale(glm::mat4(1.0f), glm::vec3(params.scale));
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    const glm::vec4 p = place * glm::vec4(mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2], 1.0f);
    for (int c = 0; c < 3; ++c) mesh.positions[3 * i + c] = p[c];
  }
  geometry::compute_vertex_normals(mesh);
  return mesh;
}

EyeCentres eye_centres(const BodyModel& model, const BodyParams& params) {
  const geometry::Mesh posed = pose_body_animal_frame(model, params);
  glm::vec3 sum[2]{glm::vec3(0), glm::vec3(0)};
  int count[2]{0, 0};
  for (std::size_t i = 0; i < posed.vertex_count(); ++i) {
    if (model.regions.empty() || model.regions[i] != region_id(Region::eyes)) continue;
    const glm::vec3 p(posed.positions[3 * i], posed.positions[3 * i + 1], posed.positions[3 * i + 2]);
    // The side from the rest pose: a turned head carries both eyes across the posed body's middle.
    const int side = model.template_vertices[3 * i] >= 0 ? 0 : 1;
    sum[side] += p, ++count[side];
  }
  if (count[0] == 0 || count[1] == 0)
    throw InputError(model.name + ": body model has no eye-region vertices on the " + (count[0] == 0 ? "left" : "right") + " side");
  const glm::mat4 place = params.animal_to_world * glm::scale(glm::mat4(1.0f), glm::vec3(params.scale));
  auto world = [&](glm::vec3 p) { return glm::vec3(place * glm::vec4(p, 1.0f)); };
  return {world(sum[0] / float(count[0])), world(sum[1] / float(count[1]))};
}

}  // namespace nf::body
