#include "engine/body/posing.hpp"

#include <cmath>

#include "engine/core/error.hpp"

namespace nf::body {
namespace {

glm::dmat3 cross_matrix(const glm::dvec3& w) {
  // Column-major: columns are the images of the unit vectors under w x.
  return glm::dmat3(glm::dvec3(0, w.z, -w.y), glm::dvec3(-w.z, 0, w.x), glm::dvec3(w.y, -w.x, 0));
}

// Contracts dL/dR with dR/d(axis-angle): central differences of Rodrigues' formula, accurate to
// ~1e-10 in double, so one formula serves every angle including zero.
glm::dvec3 rodrigues_adjoint(const glm::dvec3& w, const glm::dmat3& d_rotation) {
  constexpr double h = 1e-6;
  glm::dvec3 out(0.0);
  for (int c = 0; c < 3; ++c) {
    glm::dvec3 plus = w, minus = w;
    plus[c] += h, minus[c] -= h;
    const glm::dmat3 derivative = (rodrigues(plus) - rodrigues(minus)) / (2.0 * h);
    for (int col = 0; col < 3; ++col) out[c] += glm::dot(d_rotation[col], derivative[col]);
  }
  return out;
}

glm::dvec3 vec3_at(const std::vector<double>& x, std::size_t i) { return {x[i], x[i + 1], x[i + 2]}; }
glm::dvec3 vec3_at(const std::vector<float>& x, std::size_t i) { return {x[i], x[i + 1], x[i + 2]}; }

}  // namespace

PoseLayout PoseLayout::of(const BodyModel& model, bool with_offsets) {
  return {model.shape_count(), model.joint_count(), model.vertex_count(), with_offsets};
}

glm::dmat3 rodrigues(const glm::dvec3& w) {
  const double t2 = glm::dot(w, w), t = std::sqrt(t2);
  // R = I + a [w]x + b [w]x^2, with Taylor series where the closed forms lose digits.
  const double a = t < 1e-4 ? 1.0 - t2 / 6.0 : std::sin(t) / t;
  const double b = t < 1e-4 ? 0.5 - t2 / 24.0 : (1.0 - std::cos(t)) / t2;
  const glm::dmat3 k = cross_matrix(w);
  return glm::dmat3(1.0) + a * k + b * (k * k);
}

PoseTrace pose_forward(const BodyModel& model, const PoseLayout& L, const std::vector<double>& x) {
  NF_CHECK(x.size() == L.size(), "pose variables do not match the layout");
  const std::size_t V = L.vertices, J = L.joints, S = L.shapes;
  PoseTrace t;
  t.rest.resize(V);
  for (std::size_t i = 0; i < V; ++i) {
    glm::dvec3 p = vec3_at(model.template_vertices, 3 * i);
    for (std::size_t s = 0; s < S; ++s) {
      const double b = x[L.shape_begin() + s];
      if (b != 0.0) p += b * vec3_at(model.shape_dirs, (s * V + i) * 3);
    }
    if (L.offsets) p += vec3_at(x, L.offset_begin() + 3 * i);
    t.rest[i] = p;
  }
  t.joints.resize(J);
  for (std::size_t k = 0; k < J; ++k) {
    glm::dvec3 p = vec3_at(model.joint_template, 3 * k);
    for (std::size_t s = 0; s < S; ++s) p += x[L.shape_begin() + s] * vec3_at(model.joint_shape_dirs, (s * J + k) * 3);
    t.joints[k] = p;
  }
  t.local.resize(J), t.global.resize(J), t.skin.resize(J);
  for (std::size_t k = 0; k < J; ++k) {
    const int parent = model.parents[k];
    const glm::dvec3 offset = parent < 0 ? t.joints[k] : t.joints[k] - t.joints[std::size_t(parent)];
    glm::dmat4 local(rodrigues(vec3_at(x, L.joint_begin() + 3 * k)));
    local[3] = glm::dvec4(offset, 1.0);
    t.local[k] = local;
    t.global[k] = parent < 0 ? local : t.global[std::size_t(parent)] * local;
    glm::dmat4 skin = t.global[k];
    skin[3] = glm::dvec4(glm::dvec3(t.global[k][3]) - glm::dmat3(t.global[k]) * t.joints[k], 1.0);
    t.skin[k] = skin;
  }
  t.rotation = rodrigues(vec3_at(x, 0));
  t.translation = vec3_at(x, 3);
  t.scale = std::exp(x[6]);
  t.animal.resize(V), t.world.resize(V);
  for (std::size_t i = 0; i < V; ++i) {
    glm::dvec3 p(0.0);
    for (int k = 0; k < kSkinInfluences; ++k) {
      const double w = model.skin_weights[i * kSkinInfluences + k];
      if (w == 0.0) continue;
      const glm::dmat4& m = t.skin[model.skin_joints[i * kSkinInfluences + k]];
      p += w * (glm::dmat3(m) * t.rest[i] + glm::dvec3(m[3]));
    }
    t.animal[i] = p;
    t.world[i] = t.scale * (t.rotation * p) + t.translation;
  }
  return t;
}

void pose_backward(const BodyModel& model, const PoseLayout& L, const std::vector<double>& x, const PoseTrace& t,
                   const std::vector<glm::dvec3>& d_world, std::vector<double>& grad) {
  NF_CHECK(grad.size() == L.size() && x.size() == L.size() && d_world.size() == L.vertices &&
               t.world.size() == L.vertices && t.joints.size() == L.joints,
           "pose adjoint: sizes do not match the layout");
  const std::size_t V = L.vertices, J = L.joints, S = L.shapes;
  // world = s R animal + t
  glm::dvec3 d_translation(0.0);
  glm::dmat3 d_rotation(0.0);
  double d_scale = 0.0;
  std::vector<glm::dmat4> d_skin(J, glm::dmat4(0.0));
  std::vector<glm::dvec3> d_rest(V);
  const glm::dmat3 rt = glm::transpose(t.rotation);
  for (std::size_t i = 0; i < V; ++i) {
    const glm::dvec3 g = d_world[i];
    d_translation += g;
    const glm::dvec3 ra = t.rotation * t.animal[i];
    d_scale += glm::dot(g, ra);
    d_rotation += t.scale * glm::outerProduct(g, t.animal[i]);
    const glm::dvec3 d_animal = t.scale * (rt * g);
    // animal = sum_k w_k (M_k rest + m_k)
    glm::dvec3 dr(0.0);
    for (int k = 0; k < kSkinInfluences; ++k) {
      const double w = model.skin_weights[i * kSkinInfluences + k];
      if (w == 0.0) continue;
      const std::size_t j = model.skin_joints[i * kSkinInfluences + k];
      const glm::dmat3 m(t.skin[j]);
      dr += w * (glm::transpose(m) * d_animal);
      glm::dmat4& ds = d_skin[j];
      for (int c = 0; c < 3; ++c) ds[c] += glm::dvec4(w * t.rest[i][c] * d_animal, 0.0);
      ds[3] += glm::dvec4(w * d_animal, 0.0);
    }
    d_rest[i] = dr;
  }
  for (int c = 0; c < 3; ++c) grad[3 + std::size_t(c)] += d_translation[c];
  grad[6] += d_scale * t.scale;
  const glm::dvec3 d_global_aa = rodrigues_adjoint(vec3_at(x, 0), d_rotation);
  for (int c = 0; c < 3; ++c) grad[std::size_t(c)] += d_global_aa[c];

  // skin_k = [G33, G_t - G33 J_k]; global_k = global_parent * local_k; local_k = [R_k, offset_k].
  std::vector<glm::dmat4> d_global(J, glm::dmat4(0.0));
  std::vector<glm::dvec3> d_joints(J, glm::dvec3(0.0));
  for (std::size_t k = 0; k < J; ++k) {
    const glm::dmat3 g33(t.global[k]);
    const glm::dvec3 d_col3(d_skin[k][3]);
    glm::dmat3 dg33 = glm::dmat3(d_skin[k]) - glm::outerProduct(d_col3, t.joints[k]);
    for (int c = 0; c < 3; ++c) d_global[k][c] += glm::dvec4(dg33[c], 0.0);
    d_global[k][3] += glm::dvec4(d_col3, 0.0);
    d_joints[k] -= glm::transpose(g33) * d_col3;
  }
  for (std::size_t k = J; k-- > 0;) {
    const int parent = model.parents[k];
    glm::dmat4 d_local = d_global[k];
    if (parent >= 0) {
      const std::size_t p = std::size_t(parent);
      d_global[p] += d_global[k] * glm::transpose(t.local[k]);
      d_local = glm::transpose(t.global[p]) * d_global[k];
    }
    const glm::dvec3 d_offset(d_local[3]);
    d_joints[k] += d_offset;
    if (parent >= 0) d_joints[std::size_t(parent)] -= d_offset;
    const glm::dvec3 d_aa = rodrigues_adjoint(vec3_at(x, L.joint_begin() + 3 * k), glm::dmat3(d_local));
    for (int c = 0; c < 3; ++c) grad[L.joint_begin() + 3 * k + std::size_t(c)] += d_aa[c];
  }
  for (std::size_t s = 0; s < S; ++s) {
    double g = 0.0;
    for (std::size_t k = 0; k < J; ++k) g += glm::dot(d_joints[k], vec3_at(model.joint_shape_dirs, (s * J + k) * 3));
    for (std::size_t i = 0; i < V; ++i) g += glm::dot(d_rest[i], vec3_at(model.shape_dirs, (s * V + i) * 3));
    grad[L.shape_begin() + s] += g;
  }
  if (L.offsets)
    for (std::size_t i = 0; i < V; ++i)
      for (int c = 0; c < 3; ++c) grad[L.offset_begin() + 3 * i + std::size_t(c)] += d_rest[i][c];
}

}  // namespace nf::body
