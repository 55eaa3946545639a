#include "engine/body/smal_model.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <glm/glm.hpp>

#include "engine/body/regions.hpp"
#include "engine/core/error.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/io/npz.hpp"

namespace nf::body {
namespace {

enum class Part { torso, neck, head, muzzle, ear, leg_front, paw_front, leg_rear, paw_rear, tail };

Part part_of(const std::string& joint) {
  if (joint == "Neck") return Part::neck;
  if (joint == "Head") return Part::head;
  if (joint == "Mouth") return Part::muzzle;
  if (joint == "LEar" || joint == "REar") return Part::ear;
  if (joint.rfind("Tail", 0) == 0) return Part::tail;
  if (joint.find("FootBack") != std::string::npos) return Part::paw_rear;
  if (joint.find("LegBack") != std::string::npos) return Part::leg_rear;
  if (joint == "LFoot" || joint == "RFoot") return Part::paw_front;
  if (joint.find("Leg") != std::string::npos) return Part::leg_front;
  return Part::torso;
}

// SMAL's keypoint vertices on its 3889-vertex mesh (as SMALify uses them).
constexpr std::size_t kSmalVertices = 3889;
constexpr std::uint32_t kLeftEye = 3055, kRightEye = 1097, kNoseTip = 1863, kLeftEarTip = 150, kRightEarTip = 2124;

struct Arrays {
  const std::filesystem::path& file;
  io::NpyArray get(const std::string& name, std::size_t dims) const {
    io::NpyArray a = io::read_npz_array(file, name);
    if (a.shape.size() != dims)
      throw InputError(file.string() + ": array '" + name + "' has " + std::to_string(a.shape.size()) + " dimensions, expected " +
                       std::to_string(dims));
    for (double v : a.values)
      if (!std::isfinite(v)) throw InputError(file.string() + ": array '" + name + "' holds NaN or Inf");
    return a;
  }
  [[noreturn]] void fail(const std::string& name, const std::string& what) const {
    throw InputError(file.string() + ": array '" + name + "' " + what);
  }
};

std::string shape_text(const io::NpyArray& a) {
  std::string s;
  for (std::uint64_t d : a.shape) s += (s.empty() ? "" : ", ") + std::to_string(d);
  return "(" + s + ")";
}

}  // namespace

const std::vector<std::string>& smal_joint_names(std::size_t joints) {
  static const std::vector<std::string> smal = {
      "root",      "pelvis0",   "spine",     "spine0",    "spine1",    "spine2",    "spine3",    "LLeg1",     "LLeg2",
      "LLeg3",     "LFoot",     "RLeg1",     "RLeg2",     "RLeg3",     "RFoot",     "Neck",      "Head",      "LLegBack1",
      "LLegBack2", "LLegBack3", "LFootBack", "RLegBack1", "RLegBack2", "RLegBack3", "RFootBack", "Tail1",     "Tail2",
      "Tail3",     "Tail4",     "Tail5",     "Tail6",     "Tail7",     "Mouth"};
  static const std::vector<std::string> smalst = [] {
    std::vector<std::string> n = smal;
    n.push_back("LEar"), n.push_back("REar");
    return n;
  }();
  if (joints == smal.size()) return smal;
  if (joints == smalst.size()) return smalst;
  throw InputError("a SMAL model has 33 joints (or 35 with ears), not " + std::to_string(joints));
}

BodyModel load_smal_model(const std::filesystem::path& file) {
  const Arrays in{file};
  const io::NpyArray vt = in.get("v_template", 2), f = in.get("f", 2), sd = in.get("shapedirs", 3),
                     jr = in.get("J_regressor", 2), kt = in.get("kintree_table", 2), w = in.get("weights", 2);
  const std::size_t V = vt.shape[0], F = f.shape[0], J = jr.shape[0];
  if (V == 0 || vt.shape[1] != 3) in.fail("v_template", "has shape " + shape_text(vt) + ", expected (vertices, 3)");
  if (f.shape[1] != 3) in.fail("f", "has shape " + shape_text(f) + ", expected (faces, 3)");
  if (sd.shape[0] != V || sd.shape[1] != 3) in.fail("shapedirs", "has shape " + shape_text(sd) + ", expected (" + std::to_string(V) + ", 3, shapes)");
  if (jr.shape[1] != V) in.fail("J_regressor", "has shape " + shape_text(jr) + ", expected (joints, " + std::to_string(V) + ")");
  if (kt.shape[0] != 2 || kt.shape[1] != J) in.fail("kintree_table", "has shape " + shape_text(kt) + ", expected (2, " + std::to_string(J) + ")");
  if (w.shape[0] != V || w.shape[1] != J) in.fail("weights", "has shape " + shape_text(w) + ", expected (" + std::to_string(V) + ", " + std::to_string(J) + ")");
  const std::vector<std::string>& names = smal_joint_names(J);
  const std::size_t S = sd.shape[2];

  BodyModel m;
  m.name = "SMAL (" + file.filename().string() + ")";
  m.joint_names = names;
  m.parents.resize(J);
  for (std::size_t k = 0; k < J; ++k) {
    const double p = kt.values[k];
    // Checked before the conversion: a parent past int's range is undefined behaviour to convert.
    if (k > 0 && !(p >= 0 && p < double(k))) in.fail("kintree_table", "names parent " + std::to_string(p) + " for joint " + std::to_string(k) + " (parents come first)");
    m.parents[k] = k == 0 ? -1 : int(p);
  }
  // Joints and their shape directions through the regressor.
  std::vector<glm::dvec3> joints(J, glm::dvec3(0.0));
  std::vector<glm::dvec3> joint_dirs(S * J, glm::dvec3(0.0));
  for (std::size_t k = 0; k < J; ++k)
    for (std::size_t i = 0; i < V; ++i) {
      const double r = jr.values[k * V + i];
      if (r == 0.0) continue;
      joints[k] += r * glm::dvec3(vt.values[3 * i], vt.values[3 * i + 1], vt.values[3 * i + 2]);
      for (std::size_t s = 0; s < S; ++s)
        joint_dirs[s * J + k] += r * glm::dvec3(sd.values[(i * 3 + 0) * S + s], sd.values[(i * 3 + 1) * S + s], sd.values[(i * 3 + 2) * S + s]);
    }
  // The animal frame from the skeleton: forward from the tail root to the head, up from the paws
  // to the spine, left = up x forward.
  const auto joint = [&](const std::string& n) { return joints[std::size_t(std::find(names.begin(), names.end(), n) - names.begin())]; };
  // Up first, along the legs (they stand straight in the rest pose), then forward across it: a
  // raised head does not tilt the frame.
  const glm::dvec3 up = glm::normalize(joint("LLeg1") - joint("LFoot") + joint("RLeg1") - joint("RFoot") +
                                       joint("LLegBack1") - joint("LFootBack") + joint("RLegBack1") - joint("RFootBack"));
  glm::dvec3 forward = joint("Head") - joint("Tail1");
  forward = glm::normalize(forward - glm::dot(forward, up) * up);
  const glm::dvec3 left = glm::cross(up, forward);
  const auto to_animal = [&](const glm::dvec3& p) { return glm::dvec3(glm::dot(left, p), glm::dot(up, p), glm::dot(forward, p)); };

  m.template_vertices.resize(3 * V);
  for (std::size_t i = 0; i < V; ++i) {
    const glm::dvec3 p = to_animal({vt.values[3 * i], vt.values[3 * i + 1], vt.values[3 * i + 2]});
    for (int c = 0; c < 3; ++c) m.template_vertices[3 * i + std::size_t(c)] = float(p[c]);
  }
  m.triangles.resize(3 * F);
  for (std::size_t k = 0; k < 3 * F; ++k) {
    const double v = f.values[k];
    if (!(v >= 0 && v < double(V))) in.fail("f", "uses vertex " + std::to_string(v) + " of " + std::to_string(V));
    m.triangles[k] = std::uint32_t(v);
  }
  for (std::size_t s = 0; s < S; ++s) m.shape_names.push_back("beta" + std::to_string(s));
  m.shape_dirs.resize(S * V * 3);
  for (std::size_t s = 0; s < S; ++s)
    for (std::size_t i = 0; i < V; ++i) {
      const glm::dvec3 d = to_animal({sd.values[(i * 3 + 0) * S + s], sd.values[(i * 3 + 1) * S + s], sd.values[(i * 3 + 2) * S + s]});
      for (int c = 0; c < 3; ++c) m.shape_dirs[(s * V + i) * 3 + std::size_t(c)] = float(d[c]);
    }
  m.joint_template.resize(3 * J);
  m.joint_shape_dirs.resize(S * J * 3);
  for (std::size_t k = 0; k < J; ++k) {
    const glm::dvec3 p = to_animal(joints[k]);
    for (int c = 0; c < 3; ++c) m.joint_template[3 * k + std::size_t(c)] = float(p[c]);
    for (std::size_t s = 0; s < S; ++s) {
      const glm::dvec3 d = to_animal(joint_dirs[s * J + k]);
      for (int c = 0; c < 3; ++c) m.joint_shape_dirs[(s * J + k) * 3 + std::size_t(c)] = float(d[c]);
    }
  }
  // The four strongest skinning weights, renormalised.
  m.skin_joints.resize(V * kSkinInfluences), m.skin_weights.resize(V * kSkinInfluences);
  std::vector<std::size_t> order(J);
  for (std::size_t i = 0; i < V; ++i) {
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::partial_sort(order.begin(), order.begin() + kSkinInfluences, order.end(),
                      [&](std::size_t a, std::size_t b) { return w.values[i * J + a] > w.values[i * J + b]; });
    double sum = 0;
    for (int k = 0; k < kSkinInfluences; ++k) sum += std::max(0.0, w.values[i * J + order[std::size_t(k)]]);
    if (!(sum > 0)) in.fail("weights", "gives vertex " + std::to_string(i) + " no positive weight");
    for (int k = 0; k < kSkinInfluences; ++k) {
      m.skin_joints[i * kSkinInfluences + std::size_t(k)] = std::uint32_t(order[std::size_t(k)]);
      m.skin_weights[i * kSkinInfluences + std::size_t(k)] = float(std::max(0.0, w.values[i * J + order[std::size_t(k)]]) / sum);
    }
  }

  // Regions: the strongest joint's part, then the family's rules on normals and keypoints.
  geometry::Mesh mesh = rest_mesh(m);
  geometry::compute_vertex_normals(mesh);
  const auto vertex = [&](std::size_t i) { return glm::dvec3(m.template_vertices[3 * i], m.template_vertices[3 * i + 1], m.template_vertices[3 * i + 2]); };
  const glm::dvec3 tail_root = to_animal(joint("Tail1"));
  double tail_radius = 0;
  std::size_t tail_count = 0;
  for (std::size_t i = 0; i < V; ++i)
    if (names[m.skin_joints[i * kSkinInfluences]] == "Tail1") tail_radius += glm::distance(vertex(i), tail_root), ++tail_count;
  tail_radius = tail_count ? tail_radius / double(tail_count) : 0.0;
  const bool has_ear_joints = J == 35, keypoints = V == kSmalVertices;
  m.regions.resize(V);
  for (std::size_t i = 0; i < V; ++i) {
    const glm::dvec3 p = vertex(i), n(mesh.normals[3 * i], mesh.normals[3 * i + 1], mesh.normals[3 * i + 2]);
    const bool near_tail_root = glm::distance(p, tail_root) < 1.5 * tail_radius && p.y < tail_root.y;
    Region r = Region::body;
    switch (part_of(names[m.skin_joints[i * kSkinInfluences]])) {
      case Part::torso: r = near_tail_root ? Region::under_tail : n.y < -0.55 ? Region::belly : Region::body; break;
      case Part::neck: r = Region::neck; break;
      case Part::head:
      case Part::muzzle: r = Region::face; break;
      case Part::ear: r = n.z > 0.5 ? Region::inner_earcanal : Region::ears; break;
      case Part::leg_front: r = Region::leg_front; break;
      case Part::paw_front: r = n.y < -kPadFacing ? Region::paw_pads : Region::front_paws; break;
      case Part::leg_rear: r = Region::leg_rear; break;
      case Part::paw_rear: r = n.y < -kPadFacing ? Region::paw_pads : Region::paws; break;
      case Part::tail: r = near_tail_root ? Region::under_tail : Region::tail; break;
    }
    m.regions[i] = region_id(r);
  }
  if (keypoints) {
    const glm::dvec3 head = to_animal(joint("Head"));
    const double head_size = glm::distance(head, vertex(kNoseTip));
    for (std::size_t i = 0; i < V; ++i) {
      const glm::dvec3 p = vertex(i), n(mesh.normals[3 * i], mesh.normals[3 * i + 1], mesh.normals[3 * i + 2]);
      const Region current = Region(m.regions[i]);
      if (current != Region::face && current != Region::ears && current != Region::inner_earcanal) continue;
      if (!has_ear_joints)
        for (std::uint32_t tip : {kLeftEarTip, kRightEarTip})
          if (glm::distance(p, vertex(tip)) < 0.5 * glm::distance(vertex(tip), head))
            m.regions[i] = region_id(n.z > 0.5 ? Region::inner_earcanal : Region::ears);
      if (glm::distance(p, vertex(kNoseTip)) < 0.12 * head_size) m.regions[i] = region_id(Region::nosetip);
      for (std::uint32_t eye : {kLeftEye, kRightEye})
        if (glm::distance(p, vertex(eye)) < 0.1 * head_size) m.regions[i] = region_id(Region::eyes);
    }
  }
  m.validate(file.string());
  return m;
}

}  // namespace nf::body
