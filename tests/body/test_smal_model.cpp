// A user's SMAL model (engine/body/smal_model.hpp) on a fixture written with SMAL's exact array
// names, shapes and dtypes (3889 vertices, 33 joints, 41 shapes, posedirs of 288 bases), made from
// the procedural family so no part of SMAL ships: it loads into a BodyModel in the animal frame,
// with joints from the regressor, four skinning weights, regions without painting, and it poses.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <map>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/body/body_fit.hpp"
#include "engine/body/body_model.hpp"
#include "engine/body/region_transfer.hpp"
#include "engine/body/quadruped.hpp"
#include "engine/body/regions.hpp"
#include "engine/body/smal_model.hpp"
#include "engine/core/error.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/io/npz.hpp"

using namespace nf;
using namespace nf::body;
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kV = 3889, kJ = 33, kShapes = 41, kPoseBases = (kJ - 1) * 9;

// SMAL joint -> the procedural joint at the same place on the animal.
std::string procedural_joint(const std::string& smal, const BodyModel& p) {
  if (smal.rfind("Tail", 0) == 0) {  // Tail1.. onto tail_0.., the last ones onto the procedural tip
    int k = std::stoi(smal.substr(4)) - 1;
    while (p.joint_index("tail_" + std::to_string(k)) < 0) --k;
    return "tail_" + std::to_string(k);
  }
  static const std::map<std::string, std::string> m = {
      {"root", "pelvis"},       {"pelvis0", "pelvis"},     {"spine", "spine"},        {"spine0", "spine"},
      {"spine1", "spine"},      {"spine2", "chest"},       {"spine3", "chest"},       {"LLeg1", "shoulder_left"},
      {"LLeg2", "elbow_left"},  {"LLeg3", "wrist_left"},   {"LFoot", "wrist_left"},   {"RLeg1", "shoulder_right"},
      {"RLeg2", "elbow_right"}, {"RLeg3", "wrist_right"},  {"RFoot", "wrist_right"},  {"Neck", "neck"},
      {"Head", "head"},         {"LLegBack1", "hip_left"}, {"LLegBack2", "knee_left"}, {"LLegBack3", "ankle_left"},
      {"LFootBack", "ankle_left"}, {"RLegBack1", "hip_right"}, {"RLegBack2", "knee_right"}, {"RLegBack3", "ankle_right"},
      {"RFootBack", "ankle_right"}, {"Mouth", "muzzle"}};
  return m.at(smal);
}
// Procedural joint -> the SMAL joint its skinning weight goes to.
std::size_t smal_joint_of(const std::string& p, const std::vector<std::string>& names) {
  const auto index = [&](const std::string& n) { return std::size_t(std::find(names.begin(), names.end(), n) - names.begin()); };
  if (p.rfind("tail_", 0) == 0) return index("Tail" + std::to_string(std::min(std::stoi(p.substr(5)) + 1, 7)));
  static const std::map<std::string, std::string> m = {
      {"pelvis", "root"}, {"spine", "spine"}, {"chest", "spine3"}, {"neck", "Neck"}, {"head", "Head"}, {"muzzle", "Mouth"},
      {"nose", "Mouth"}, {"ear_left", "Head"}, {"ear_right", "Head"}, {"ear_left_tip", "Head"}, {"ear_right_tip", "Head"},
      {"shoulder_left", "LLeg1"}, {"elbow_left", "LLeg2"}, {"wrist_left", "LFoot"}, {"shoulder_right", "RLeg1"},
      {"elbow_right", "RLeg2"}, {"wrist_right", "RFoot"}, {"hip_left", "LLegBack1"}, {"knee_left", "LLegBack2"},
      {"ankle_left", "LFootBack"}, {"hip_right", "RLegBack1"}, {"knee_right", "RLegBack2"}, {"ankle_right", "RFootBack"}};
  return index(m.at(p));
}

struct Fixture {
  fs::path file = fs::temp_directory_path() / "nf_test_smal_fixture.npz";
  BodyModel source;
  glm::dmat3 file_axes;  // animal frame -> the file's axes (SMAL files are not in nf_gpu's frame)
};

// Writes the fixture in a z-up, x-forward frame, as a foreign model would come.
Fixture write_fixture(const std::vector<std::string>& drop = {}, const std::string& wrong_shape = "") {
  Fixture fx;
  QuadrupedBuildOptions o;
  o.voxel = 0.015f;
  fx.source = build_quadruped(animal_proportions("dog"), o);
  const BodyModel& p = fx.source;
  REQUIRE(p.vertex_count() < kV);  // padded below with copies that no face uses
  fx.file_axes = glm::dmat3(glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1), glm::dvec3(1, 0, 0));  // x left->y, y up->z, z fwd->x
  const auto out = [&](std::size_t i) {
    return fx.file_axes * glm::dvec3(p.template_vertices[3 * i], p.template_vertices[3 * i + 1], p.template_vertices[3 * i + 2]);
  };
  // Which procedural vertex each of the 3889 is: the model's own, then copies; SMAL's keypoint
  // vertices are copies of the procedural eyes, nose tip and ear tips.
  std::vector<std::size_t> source_of(kV);
  for (std::size_t i = 0; i < kV; ++i) source_of[i] = i % p.vertex_count();
  const auto nearest_to_joint = [&](const std::string& joint, int region) {
    const int j = p.joint_index(joint);
    const glm::dvec3 at(p.joint_template[3 * std::size_t(j)], p.joint_template[3 * std::size_t(j) + 1], p.joint_template[3 * std::size_t(j) + 2]);
    std::size_t best = 0;
    double d = 1e30;
    for (std::size_t i = 0; i < p.vertex_count(); ++i) {
      if (region >= 0 && p.regions[i] != region) continue;
      const double e = glm::distance(at, glm::dvec3(p.template_vertices[3 * i], p.template_vertices[3 * i + 1], p.template_vertices[3 * i + 2]));
      if (e < d) d = e, best = i;
    }
    return best;
  };
  std::size_t left_eye = 0, right_eye = 0;
  for (std::size_t i = 0; i < p.vertex_count(); ++i)
    if (p.regions[i] == region_id(Region::eyes)) (p.template_vertices[3 * i] > 0 ? left_eye : right_eye) = i;
  source_of[3055] = left_eye, source_of[1097] = right_eye;
  source_of[1863] = nearest_to_joint("nose", region_id(Region::nosetip));
  source_of[150] = nearest_to_joint("ear_left_tip", -1), source_of[2124] = nearest_to_joint("ear_right_tip", -1);
  // Faces refer to the procedural vertices, which keep their indices (the copies come after them)
  // except where a keypoint copy overwrote one: those faces move to the copy's twin.
  std::vector<std::size_t> home(p.vertex_count());
  for (std::size_t i = 0; i < p.vertex_count(); ++i) home[i] = i;
  for (std::size_t k : {std::size_t(3055), std::size_t(1097), std::size_t(1863), std::size_t(150), std::size_t(2124)})
    if (k < p.vertex_count()) home[k] = k + p.vertex_count() < kV ? k + p.vertex_count() : k;

  const std::vector<std::string>& names = smal_joint_names(kJ);
  std::vector<io::NpyWrite> arrays;
  io::NpyWrite vt{"v_template", {kV, 3}, "<f8", {}};
  for (std::size_t i = 0; i < kV; ++i) {
    const glm::dvec3 q = out(source_of[i]);
    vt.values.insert(vt.values.end(), {q.x, q.y, q.z});
  }
  io::NpyWrite f{"f", {p.triangles.size() / 3, 3}, "<u4", {}};
  for (std::uint32_t v : p.triangles) f.values.push_back(double(home[v]));
  io::NpyWrite sd{"shapedirs", {kV, 3, kShapes}, "<f8", std::vector<double>(kV * 3 * kShapes, 0.0)};
  for (std::size_t i = 0; i < kV; ++i)
    for (std::size_t s = 0; s < p.shape_count(); ++s) {
      const std::size_t q = source_of[i];
      const glm::dvec3 d = fx.file_axes * glm::dvec3(p.shape_dirs[(s * p.vertex_count() + q) * 3], p.shape_dirs[(s * p.vertex_count() + q) * 3 + 1],
                                                     p.shape_dirs[(s * p.vertex_count() + q) * 3 + 2]);
      for (int c = 0; c < 3; ++c) sd.values[(i * 3 + std::size_t(c)) * kShapes + s] = d[c];
    }
  // Each joint as SMAL's regressor makes it: an affine combination of nearby vertices (here the
  // least-norm one of the 8 nearest that reproduces the procedural joint exactly).
  io::NpyWrite jr{"J_regressor", {kJ, kV}, "<f8", std::vector<double>(kJ * kV, 0.0)};
  const geometry::PointIndex index(p.template_vertices);
  for (std::size_t k = 0; k < kJ; ++k) {
    const int j = p.joint_index(procedural_joint(names[k], p));
    const float* at = &p.joint_template[3 * std::size_t(j)];
    const std::vector<std::uint32_t> near = index.nearest_k(at, 8);
    glm::dmat4 aat(0.0);  // A A^T with A = [v_i; 1] (4 x 8)
    for (std::uint32_t v : near) {
      const glm::dvec4 a(p.template_vertices[3 * v], p.template_vertices[3 * v + 1], p.template_vertices[3 * v + 2], 1.0);
      aat += glm::outerProduct(a, a);
    }
    const glm::dvec4 y = glm::inverse(aat) * glm::dvec4(at[0], at[1], at[2], 1.0);
    for (std::uint32_t v : near)
      jr.values[k * kV + v] = glm::dot(y, glm::dvec4(p.template_vertices[3 * v], p.template_vertices[3 * v + 1], p.template_vertices[3 * v + 2], 1.0));
  }
  io::NpyWrite kt{"kintree_table", {2, kJ}, "<i8", {}};
  const std::vector<int> parents = {-1, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 6, 11, 12, 13, 6, 15, 0, 17, 18, 19, 0, 21, 22, 23, 0, 25, 26, 27, 28, 29, 30, 16};
  for (int q : parents) kt.values.push_back(q < 0 ? 4294967295.0 : double(q));
  for (std::size_t k = 0; k < kJ; ++k) kt.values.push_back(double(k));
  io::NpyWrite w{"weights", {kV, kJ}, "<f8", std::vector<double>(kV * kJ, 0.0)};
  for (std::size_t i = 0; i < kV; ++i)
    for (int k = 0; k < kSkinInfluences; ++k) {
      const std::size_t q = source_of[i];
      const std::size_t j = smal_joint_of(p.joint_names[p.skin_joints[q * 4 + std::size_t(k)]], names);
      w.values[i * kJ + j] += p.skin_weights[q * 4 + std::size_t(k)];
    }
  io::NpyWrite pd{"posedirs", {kV, 3, kPoseBases}, "<f8", std::vector<double>(kV * 3 * kPoseBases, 0.0)};
  for (io::NpyWrite* a : {&vt, &f, &sd, &jr, &kt, &w, &pd}) {
    if (std::find(drop.begin(), drop.end(), a->name) != drop.end()) continue;
    if (a->name == wrong_shape) {  // two coordinates instead of three
      a->shape[1] = 2;
      std::size_t count = 1;
      for (std::uint64_t d : a->shape) count *= d;
      a->values.resize(count);
    }
    arrays.push_back(*a);
  }
  fs::remove(fx.file);
  io::write_npz(fx.file, arrays);
  return fx;
}

}  // namespace

TEST_CASE("a SMAL-layout .npz loads into the animal frame with joints, weights and regions") {
  const Fixture fx = write_fixture();
  const BodyModel m = load_smal_model(fx.file);
  CHECK(m.vertex_count() == kV);
  CHECK(m.joint_count() == kJ);
  CHECK(m.shape_count() == kShapes);
  CHECK(m.joint_names[16] == "Head");
  CHECK(m.parents[0] == -1);
  CHECK(m.parents[32] == 16);
  // Back in the animal frame: the vertices are where the procedural model had them (the file's axes
  // undone; the skeleton's legs and head-tail line give the frame to within a few degrees).
  for (std::size_t i = 0; i < fx.source.vertex_count(); i += 97)
    for (int c = 0; c < 3; ++c)
      CHECK(std::abs(m.template_vertices[3 * i + std::size_t(c)] - fx.source.template_vertices[3 * i + std::size_t(c)]) < 0.02f);
  // Head in front of the tail, paws below the spine, the left legs on +x.
  const auto joint = [&](const char* n) {
    const int j = m.joint_index(n);
    return glm::vec3(m.joint_template[3 * std::size_t(j)], m.joint_template[3 * std::size_t(j) + 1], m.joint_template[3 * std::size_t(j) + 2]);
  };
  CHECK(joint("Head").z > joint("Tail1").z);
  CHECK(joint("LFoot").y < joint("spine").y);
  CHECK(joint("LLeg1").x > 0);
  CHECK(joint("RLeg1").x < 0);
  for (std::size_t i = 0; i < kV; ++i) {
    float sum = 0;
    for (int k = 0; k < kSkinInfluences; ++k) sum += m.skin_weights[i * 4 + std::size_t(k)];
    REQUIRE(sum == doctest::Approx(1.0f).epsilon(1e-5));
  }
  std::map<int, int> counts;
  for (std::int32_t r : m.regions) ++counts[r];
  for (Region r : {Region::face, Region::eyes, Region::nosetip, Region::ears, Region::leg_front, Region::leg_rear, Region::tail,
                   Region::body, Region::belly, Region::paw_pads})
    CHECK_MESSAGE(counts[region_id(r)] > 0, region_name(region_id(r)));
  CHECK(m.regions[3055] == region_id(Region::eyes));
  CHECK(m.regions[1863] == region_id(Region::nosetip));
  // It poses: the eyes are found on both sides, as the body stage needs them.
  const EyeCentres eyes = eye_centres(m, BodyParams{});
  CHECK(eyes.left.x > 0);
  CHECK(eyes.right.x < 0);
  fs::remove(fx.file);
}

TEST_CASE("the body fit takes a SMAL-layout model as it takes the family's template") {
  const Fixture fx = write_fixture();
  const BodyModel smal = load_smal_model(fx.file);
  fs::remove(fx.file);
  const BodyModel animal = build_quadruped(vary_proportions(animal_proportions("dog"), 4), {});
  const geometry::Mesh target = pose_body(animal, random_pose(animal, 2));
  BodyFitOptions o;
  o.samples = 4000, o.hypothesis_steps = 20, o.global_steps = 40, o.pose_steps = 80, o.offset_steps = 30;
  const BodyFit fit = fit_body(smal, target, FrameHints{glm::dvec3(0, 1, 0)}, o, "dog");
  geometry::Mesh labelled = target;
  labelled.regions = nearest_regions(target, fit.fitted);
  const double accuracy = region_accuracy(labelled, target).accuracy;
  MESSAGE("SMAL-layout fixture fitted to a procedural dog: label accuracy " << 100 * accuracy << " %");
  CHECK(accuracy > 0.85);
  CHECK_FALSE(fit.low_confidence);
}

TEST_CASE("a SMAL file with a missing array or a wrong shape is refused by name") {
  {
    const Fixture fx = write_fixture({"J_regressor"});
    CHECK_THROWS_WITH_AS(load_smal_model(fx.file), doctest::Contains("array 'J_regressor' is missing"), InputError);
    fs::remove(fx.file);
  }
  {
    const Fixture fx = write_fixture({}, "shapedirs");
    CHECK_THROWS_WITH_AS(load_smal_model(fx.file), doctest::Contains("array 'shapedirs' has shape (3889, 2,"), InputError);
    fs::remove(fx.file);
  }
  CHECK_THROWS_WITH_AS(load_smal_model("/nonexistent/smal.npz"), doctest::Contains("/nonexistent/smal.npz"), InputError);
}
