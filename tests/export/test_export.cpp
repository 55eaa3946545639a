// The export frame, the rig carried to another surface, posing and per-region edits:
// - a z-up scene in millimetres exports the same upright animal in metres as a y-up one;
// - weights carried from the body model to its own surface are the model's weights;
// - skinning: no rotation is the identity, a rotated joint turns what it owns about itself;
// - a strand follows its root face rigidly;
// - edits: lengths scale by the asked factor, shaved regions vanish, density keeps or adds roots
//   of that region only, other regions' roots are untouched.
#include <doctest/doctest.h>

#include <cmath>

#include "engine/body/body_fit.hpp"
#include "engine/body/posing.hpp"
#include "engine/core/error.hpp"
#include "engine/export/body_rig.hpp"
#include "engine/export/export_frame.hpp"
#include "engine/export/pose_groom.hpp"
#include "engine/export/region_edits.hpp"
#include "engine/fur/roots.hpp"
#include "engine/geometry/mesh_tools.hpp"

using namespace nf;
using namespace nf::exporter;

namespace {

geometry::Mesh box_mesh(glm::vec3 lo, glm::vec3 hi) {
  geometry::Mesh m;
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 p((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
    m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
  }
  m.triangles = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  return m;
}

}  // namespace

TEST_CASE("the export frame: the animal upright in metres, whatever the scene's axes and unit") {
  // A scene with z up in millimetres: the animal's left is world +x, up world +z, forward world -y;
  // the animal frame is scaled (its columns have length 250, as a fit in mm would give).
  const double s = 250;
  glm::dmat4 a(1.0);
  a[0] = glm::dvec4(s, 0, 0, 0), a[1] = glm::dvec4(0, 0, s, 0), a[2] = glm::dvec4(0, -s, 0, 0), a[3] = glm::dvec4(100, 200, 300, 1);
  const geometry::Mesh body = box_mesh({0, 100, 250}, {200, 300, 600});  // mm
  const ExportFrame f = export_frame(a, 0.1, body);  // 0.1 cm per unit: millimetres
  CHECK(f.metres_per_unit == doctest::Approx(0.001));
  CHECK(glm::distance(f.direction({0, 0, 1}), glm::vec3(0, 1, 0)) < 1e-6f);   // world up -> +y
  CHECK(glm::distance(f.direction({0, -1, 0}), glm::vec3(0, 0, 1)) < 1e-6f);  // forward -> +z
  CHECK(glm::distance(f.direction({1, 0, 0}), glm::vec3(1, 0, 0)) < 1e-6f);   // left -> +x
  const geometry::Bounds b = geometry::mesh_bounds(to_export(body, f));
  CHECK(b.lo.y == doctest::Approx(0.0).epsilon(1e-6));                 // standing on the ground
  CHECK(b.hi.y - b.lo.y == doctest::Approx(0.35).epsilon(1e-5));       // 350 mm tall
  CHECK(b.hi.x - b.lo.x == doctest::Approx(0.2).epsilon(1e-5));
  // The same animal in a y-up scene in metres exports to the same place.
  glm::dmat4 a2(1.0);
  a2[0] = glm::dvec4(0.25, 0, 0, 0), a2[1] = glm::dvec4(0, 0.25, 0, 0), a2[2] = glm::dvec4(0, 0, 0.25, 0), a2[3] = glm::dvec4(0.1, 0.3, -0.2, 1);
  geometry::Mesh body_m;
  for (std::size_t v = 0; v < body.vertex_count(); ++v) {  // the same points: x, z, -y in metres
    const glm::vec3 p = body.position(v) * 0.001f;
    body_m.positions.insert(body_m.positions.end(), {p.x, p.z, -p.y});
  }
  body_m.triangles = body.triangles;
  const ExportFrame f2 = export_frame(a2, 100, body_m);
  for (std::size_t v = 0; v < body.vertex_count(); ++v)
    CHECK(glm::distance(f.point(body.position(v)), f2.point(body_m.position(v))) < 1e-5f);
  CHECK_THROWS_AS(export_frame(a, 0, body), InputError);
  CHECK_THROWS_AS(export_frame(glm::dmat4(0.0), 1, body), InputError);
}

TEST_CASE("the rig on the body model's own surface carries the model's weights; posing moves what a joint owns") {
  const body::BodyModel model = body::default_template();
  body::BodyFit fit;
  fit.variables.assign(body::PoseLayout::of(model, true).size(), 0.0);
  const geometry::Mesh surface = fitted_body_world(model, fit);
  ExportFrame frame;  // identity
  const io::Skeleton rig = transfer_rig(model, fit, surface, frame);
  rig.validate("rig", surface.vertex_count());
  REQUIRE(rig.joint_count() == model.joint_count());
  int same = 0;
  for (std::size_t v = 0; v < surface.vertex_count(); ++v) {
    // Joint -> weight of the model and of the rig agree.
    double diff = 0;
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t j = model.skin_joints[4 * v + std::size_t(k)];
      float w_rig = 0;
      for (int q = 0; q < 4; ++q)
        if (rig.skin_joints[4 * v + std::size_t(q)] == j) w_rig += rig.skin_weights[4 * v + std::size_t(q)];
      diff += std::abs(double(w_rig) - model.skin_weights[4 * v + std::size_t(k)]);
    }
    same += diff < 1e-4;
  }
  CHECK(same >= int(0.999 * double(surface.vertex_count())));

  // No rotation: the identity. A rotation of the head: the head vertices turn about the head joint,
  // the rump stays.
  const std::vector<glm::mat4> rest = skinning_transforms(rig, {});
  const geometry::Mesh unposed = skin_mesh(surface, rig, rest);
  for (std::size_t i = 0; i < surface.positions.size(); ++i) REQUIRE(unposed.positions[i] == doctest::Approx(surface.positions[i]).epsilon(1e-6));
  const int head = model.joint_index("head");
  REQUIRE(head >= 0);
  std::vector<glm::vec3> rotations(rig.joint_count(), glm::vec3(0.f));
  rotations[std::size_t(head)] = glm::vec3(0, 0.5f, 0);
  const geometry::Mesh turned = skin_mesh(surface, rig, skinning_transforms(rig, rotations));
  const glm::vec3 pivot = rig.joint_positions[std::size_t(head)];
  // The head and the joints below it turn together.
  std::vector<bool> under_head(rig.joint_count(), false);
  for (std::size_t j = 0; j < rig.joint_count(); ++j)
    under_head[j] = int(j) == head || (rig.parents[j] >= 0 && under_head[std::size_t(rig.parents[j])]);
  int head_only = 0, moved_rump = 0, rigid = 0;
  for (std::size_t v = 0; v < surface.vertex_count(); ++v) {
    float w = 0;
    for (int k = 0; k < 4; ++k)
      if (under_head[rig.skin_joints[4 * v + std::size_t(k)]]) w += rig.skin_weights[4 * v + std::size_t(k)];
    const float moved = glm::distance(turned.position(v), surface.position(v));
    if (w > 0.999f) {
      ++head_only;
      // Distance to the pivot is kept (a rotation about it).
      rigid += std::abs(glm::distance(turned.position(v), pivot) - glm::distance(surface.position(v), pivot)) < 1e-4f;
    } else if (w == 0.f && surface.position(v).z < pivot.z - 0.5f * (pivot.z - geometry::mesh_bounds(surface).lo.z)) {
      moved_rump += moved > 1e-6f;
    }
  }
  CHECK(head_only > 10);
  CHECK(rigid == head_only);
  CHECK(moved_rump == 0);
}

TEST_CASE("a strand follows its root face rigidly") {
  geometry::Mesh rest;
  rest.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  rest.triangles = {0, 1, 2};
  const glm::mat4 r = glm::mat4(glm::mat3(0.36f, 0.48f, -0.8f, -0.8f, 0.6f, 0.f, 0.48f, 0.64f, 0.6f));  // a rotation
  geometry::Mesh posed = rest;
  for (std::size_t v = 0; v < 3; ++v) {
    const glm::vec3 p = glm::vec3(r * glm::vec4(rest.position(v), 1.f)) + glm::vec3(2, 3, 4);
    posed.positions[3 * v] = p.x, posed.positions[3 * v + 1] = p.y, posed.positions[3 * v + 2] = p.z;
  }
  const RootMotion m = root_motion(rest, posed, 0, {0.2f, 0.3f, 0.5f});
  for (const glm::vec3 p : {glm::vec3(0.3f, 0.5f, 0.f), glm::vec3(0.3f, 0.5f, 0.4f), glm::vec3(-1, 2, 3)}) {
    const glm::vec3 want = glm::vec3(r * glm::vec4(p, 1.f)) + glm::vec3(2, 3, 4);
    CHECK(glm::distance(m.apply(p), want) < 1e-5f);
  }
}

TEST_CASE("region edits: lengths scale, shave removes, density keeps or adds that region only") {
  // A strip of two regions: faces 0-99 tail, 100-199 body.
  geometry::Mesh m;
  for (int i = 0; i <= 100; ++i) m.positions.insert(m.positions.end(), {float(i), 0.f, 0.f, float(i), 1.f, 0.f});
  for (std::uint32_t i = 0; i < 100; ++i) m.triangles.insert(m.triangles.end(), {2 * i, 2 * i + 2, 2 * i + 1, 2 * i + 1, 2 * i + 2, 2 * i + 3});
  defur::VertexFur fur;
  const auto tail = body::region_id(body::Region::tail), back = body::region_id(body::Region::body);
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    fur.region.push_back(v < 101 ? tail : back);
    fur.length.push_back(0.05f);
    fur.direction.push_back({1, 0, 0});
  }
  fur::FaceFrames frames;
  frames.tangent.assign(m.triangle_count(), {1, 0, 0});
  frames.normal.assign(m.triangle_count(), {0, 0, 1});
  const fur::Roots roots = fur::sample_roots(m, frames, fur, 4000, 3);
  knowledge::Knowledge k = knowledge::preset("cat");
  const double tail_cm = k.at(body::Region::tail).length_cm;
  std::size_t tails = 0;
  for (std::int32_t r : roots.region) tails += r == tail;
  REQUIRE(tails > 1000);

  GroomEdits longer = GroomEdits::parse({"tail.length_cm=" + std::to_string(2 * tail_cm)}, {});
  const fur::Roots a = edit_roots(roots, longer, k, m, frames, fur, 1);
  REQUIRE(a.size() == roots.size());
  for (std::size_t i = 0; i < roots.size(); ++i) {
    if (roots.region[i] == tail) CHECK(a.length[i] == doctest::Approx(2 * roots.length[i]).epsilon(1e-6));
    else REQUIRE(a.length[i] == roots.length[i]);
    REQUIRE(a.position[i] == roots.position[i]);
  }
  const fur::Roots shaved = edit_roots(roots, GroomEdits::parse({}, {"tail"}), k, m, frames, fur, 1);
  CHECK(shaved.size() == roots.size() - tails);
  for (std::int32_t r : shaved.region) REQUIRE(r != tail);
  const fur::Roots thin = edit_roots(roots, GroomEdits::parse({"tail.density=0.5"}, {}), k, m, frames, fur, 1);
  std::size_t thin_tails = 0;
  for (std::int32_t r : thin.region) thin_tails += r == tail;
  CHECK(double(thin_tails) == doctest::Approx(0.5 * double(tails)).epsilon(0.08));
  CHECK(thin.size() - thin_tails == roots.size() - tails);
  const fur::Roots thick = edit_roots(roots, GroomEdits::parse({"tail.density=2"}, {}), k, m, frames, fur, 1);
  std::size_t thick_tails = 0;
  for (std::size_t i = 0; i < thick.size(); ++i) {
    thick_tails += thick.region[i] == tail;
    if (i >= roots.size()) CHECK(thick.position[i].x <= 100.5f);  // the added roots lie on the tail's faces
  }
  CHECK(thick_tails == 2 * tails);
  // The untouched region keeps its roots, in order.
  std::vector<glm::vec3> before, after;
  for (std::size_t i = 0; i < roots.size(); ++i) if (roots.region[i] == back) before.push_back(roots.position[i]);
  for (std::size_t i = 0; i < thick.size(); ++i) if (thick.region[i] == back) after.push_back(thick.position[i]);
  CHECK(before == after);

  CHECK_THROWS_WITH_AS(GroomEdits::parse({"tial.length_cm=3"}, {}), doctest::Contains("'tial' is not a region"), UsageError);
  CHECK_THROWS_WITH_AS(GroomEdits::parse({"tail.lenght_cm=3"}, {}), doctest::Contains("unknown field"), UsageError);
  CHECK_THROWS_WITH_AS(GroomEdits::parse({"tail.length_cm=-1"}, {}), doctest::Contains("must lie in"), UsageError);
  CHECK_THROWS_WITH_AS(GroomEdits::parse({"tail.density=x"}, {}), doctest::Contains("not a number"), UsageError);
  const auto widths = region_hair_diameter_mm(k, GroomEdits::parse({"tail.hair_diameter_mm=0.5"}, {}));
  CHECK(widths[std::size_t(tail)] == doctest::Approx(0.5));
  CHECK(widths[std::size_t(back)] == doctest::Approx(k.hair_diameter_mm));  // the animal's, not the layer's thickness
  CHECK(k.hair_diameter_mm < 0.2f);
  // The fur layer's depth is M_bald's; edit refuses it and says where it lives.
  CHECK_THROWS_WITH_AS(GroomEdits::parse({"tail.thickness_cm=0.5"}, {}), doctest::Contains("rerun `reconstruct --from defur`"), UsageError);
}
