// One scene in two world frames. `nf_gpu synth --frame z-up-mm` writes the same animal and the same
// photos as the default frame (y up, metres), with every coordinate in a studio's convention: z up,
// millimetres, metres from the origin. The pipeline must find frame, units and scale from the data,
// so each stage's ground-truth figures (in cm, mm and degrees) must agree between the two runs, and
// the export (upright, metres) must be the same animal. A constant tied to metres or to y up would
// make them part. The surface stage takes the true envelope (neus.mesh), so that NeuS's run-to-run
// noise (float atomics in its adjoint) does not blur the comparison.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include <glm/glm.hpp>

#include "engine/core/json.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/strand_files.hpp"
#include "tests/support/nf_process.hpp"

namespace fs = std::filesystem;
using nf::json;
using namespace nf::test;

namespace {

json stages_of(const Result& r) { return nf::test::json_of(r); }

json summary(const json& stages, const std::string& name) {
  for (const json& s : stages)
    if (s["stage"] == name) return s["summary"];
  FAIL("no stage " << name);
  return json();
}

json read_json(const fs::path& file) { return json::parse(slurp(file)); }

struct Box {
  glm::dvec3 lo{1e300}, hi{-1e300};
  void add(const glm::dvec3& p) { lo = glm::min(lo, p), hi = glm::max(hi, p); }
  glm::dvec3 size() const { return hi - lo; }
};

Box box_of(const std::vector<float>& xyz) {
  Box b;
  for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) b.add({xyz[i], xyz[i + 1], xyz[i + 2]});
  return b;
}

double angle_deg(const glm::dvec3& a, const glm::dvec3& b) {
  return std::acos(std::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.0, 1.0)) * 180.0 / 3.14159265358979;
}

}  // namespace

TEST_CASE("the same scene in z-up millimetres reconstructs as in y-up metres, stage by stage") {
  const fs::path root = fs::temp_directory_path() / "nf_cli_other_frames";
  fs::remove_all(root);
  const std::map<std::string, fs::path> scene{{"y-up-m", root / "y_up_m"}, {"z-up-mm", root / "z_up_mm"}};
  for (const auto& [frame, dir] : scene)
    REQUIRE(run("synth --animal cat --views 8 --res 64 --strands 4000 --spp-axis 1 --frame " + frame + " --out " + dir.string()).code == 0);
  const fs::path m = scene.at("y-up-m"), mm = scene.at("z-up-mm");
  CHECK(run("synth --animal cat --frame x-up-ft --out " + (root / "bad").string()).code == 2);

  // The files: the same photos and masks; the truth's coordinates are x' = 1000 R x + t.
  for (int v = 0; v < 8; ++v) {
    char name[16];
    std::snprintf(name, sizeof name, "%03d.png", v);
    CHECK_MESSAGE(slurp(m / "images" / name) == slurp(mm / "images" / name), name);
    CHECK_MESSAGE(slurp(m / "masks" / name) == slurp(mm / "masks" / name), name);
  }
  CHECK(read_json(m / "transforms.json")["cm_per_unit"].get<double>() == doctest::Approx(100.0));
  CHECK(read_json(mm / "transforms.json")["cm_per_unit"].get<double>() == doctest::Approx(0.1));
  CHECK(read_json(mm / "gt" / "scene.json")["frame"] == "z-up-mm");
  const nf::io::StrandSet truth_m = nf::io::read_hair(m / "gt" / "strands.hair"), truth_mm = nf::io::read_hair(mm / "gt" / "strands.hair");
  REQUIRE(truth_m.points.size() == truth_mm.points.size());
  const glm::dmat3 rotation(glm::dvec3(1, 0, 0), glm::dvec3(0, 0, 1), glm::dvec3(0, -1, 0));  // y up -> z up
  const glm::dvec3 offset(1500, -2500, 400);
  double worst_mm = 0;
  for (std::size_t i = 0; i < truth_m.points.size(); i += 3) {
    const glm::dvec3 a(truth_m.points[i], truth_m.points[i + 1], truth_m.points[i + 2]);
    const glm::dvec3 b(truth_mm.points[i], truth_mm.points[i + 1], truth_mm.points[i + 2]);
    worst_mm = std::max(worst_mm, glm::distance(1000.0 * (rotation * a) + offset, b));
  }
  CHECK(worst_mm < 0.01);

  // The whole pipeline, small, on each.
  const std::string settings =
      " --quality draft --set knowledge.preset=cat --set body.samples=2000 --set body.hypothesis_steps=8 --set body.global_steps=10"
      " --set body.pose_steps=20 --set body.offset_steps=10 --set body.preview_views=0 --set defur.resolution=64"
      " --set defur.preview_views=0 --set frames.roots=3000 --set fur.steps=12 --set fur.warm_steps=4 --set fur.batch=400"
      " --set fur.strands=2500 --set fur.metric_strands=1500 --set fur.resolution=64 --set fur.preview_views=0"
      " --set fur.chamfer_queries=500 --set export.turntable_frames=0 --set export.compare_views=0";
  std::map<std::string, json> stages;
  for (const auto& [frame, dir] : scene) {
    const Result r = run("reconstruct --scene " + dir.string() + " --out " + (root / (frame + "_work")).string() + settings +
                         " --set neus.mesh=" + (dir / "gt" / "outer.ply").string() + " --json");
    INFO(r.output);
    REQUIRE(r.code == 0);
    stages[frame] = stages_of(r);
  }
  const json &a = stages.at("y-up-m"), &b = stages.at("z-up-mm");
  const fs::path work_m = root / "y-up-m_work", work_mm = root / "z-up-mm_work";

  // body: the same labels on the envelope.
  const double acc_m = summary(a, "body")["ground_truth"]["accuracy"].get<double>(),
               acc_mm = summary(b, "body")["ground_truth"]["accuracy"].get<double>();
  MESSAGE("body label accuracy: ", acc_m, " / ", acc_mm);
  CHECK(acc_m > 0.5);
  CHECK(std::abs(acc_m - acc_mm) < 0.05);

  // knowledge: the scene's unit, and the same animal frame turned with the world.
  const json km = summary(a, "knowledge"), kmm = summary(b, "knowledge");
  CHECK(km["scale"]["cm_per_unit"].get<double>() == doctest::Approx(100.0));
  CHECK(kmm["scale"]["cm_per_unit"].get<double>() == doctest::Approx(0.1));
  CHECK(kmm["scale"]["source"] == "scene");
  for (const char* axis : {"up", "forward", "left"}) {
    const double e_m = km["ground_truth"]["frame_error_degrees"][axis].get<double>(),
                 e_mm = kmm["ground_truth"]["frame_error_degrees"][axis].get<double>();
    MESSAGE("animal frame error, ", std::string(axis), ": ", e_m, " / ", e_mm, " deg");
    CHECK(e_mm < 15.0);
    CHECK(std::abs(e_m - e_mm) < 3.0);
  }
  const json dir_m = read_json(work_m / "knowledge" / "directions_world.json")["directions"],
             dir_mm = read_json(work_mm / "knowledge" / "directions_world.json")["directions"];
  int compared = 0;
  for (const auto& [region, d] : dir_m.items()) {
    const glm::dvec3 u(d[0].get<double>(), d[1].get<double>(), d[2].get<double>());
    const json& e = dir_mm.at(region);
    const glm::dvec3 w(e[0].get<double>(), e[1].get<double>(), e[2].get<double>());
    if (glm::length(u) < 0.5) continue;
    CHECK_MESSAGE(angle_deg(rotation * u, w) < 6.0, region);
    ++compared;
  }
  CHECK(compared > 8);

  // defur and frames: the bald body as far from the truth in mm, the tangent field as close in degrees.
  const double bald_m = summary(a, "defur")["ground_truth"]["bald"]["chamfer_mm"]["mean"].get<double>(),
               bald_mm = summary(b, "defur")["ground_truth"]["bald"]["chamfer_mm"]["mean"].get<double>();
  MESSAGE("M_bald to the true body: ", bald_m, " / ", bald_mm, " mm");
  CHECK(bald_mm < 10.0);
  CHECK(std::abs(bald_m - bald_mm) < 0.15 * bald_m + 0.2);
  const double field_m = summary(a, "frames")["ground_truth"]["field_mean_angle_deg"].get<double>(),
               field_mm = summary(b, "frames")["ground_truth"]["field_mean_angle_deg"].get<double>();
  MESSAGE("tangent field against the true strands: ", field_m, " / ", field_mm, " deg");
  CHECK(std::abs(field_m - field_mm) < 2.0);

  // fur: the baseline groom on the pipeline's roots scores the same against the truth (its
  // thresholds are in cm and mm), the true groom scores the same against the held-out photos, and
  // the optimised groom's tips lie as close to the true envelope.
  const json fm = summary(a, "fur"), fmm = summary(b, "fur");
  for (const char* t : {"2cm_20deg", "2mm_20deg", "4mm_40deg"}) {
    const double f_m = fm["baseline"]["fscore"][t].get<double>(), f_mm = fmm["baseline"]["fscore"][t].get<double>();
    MESSAGE("baseline F-score ", std::string(t), ": ", f_m, " / ", f_mm);
    CHECK(std::abs(f_m - f_mm) < 4.0);
  }
  CHECK(fm["baseline"]["fscore"]["2cm_20deg"].get<double>() > 50.0);
  CHECK(fmm["held_out"]["truth"]["orientation_error_deg"].get<double>() ==
        doctest::Approx(fm["held_out"]["truth"]["orientation_error_deg"].get<double>()).epsilon(0.01));
  const double tips_m = fm["groom"]["tips_to_outer"]["two_way_mm"].get<double>(),
               tips_mm = fmm["groom"]["tips_to_outer"]["two_way_mm"].get<double>();
  MESSAGE("groom tips to the true envelope, two-way: ", tips_m, " / ", tips_mm, " mm");
  CHECK(tips_mm < 3.0 * tips_m + 2.0);
  CHECK(tips_m < 3.0 * tips_mm + 2.0);
  CHECK(read_json(work_mm / "fur" / "scale.json")["cm_per_unit"].get<double>() == doctest::Approx(0.1));

  // export: upright, in metres, on the ground: the same animal from both frames.
  const nf::geometry::Mesh body_m = nf::io::read_mesh_gltf(work_m / "export" / "body.glb"),
                           body_mm = nf::io::read_mesh_gltf(work_mm / "export" / "body.glb");
  const Box bm = box_of(body_m.positions), bmm = box_of(body_mm.positions);
  MESSAGE("exported body, metres: ", bm.size().x, " x ", bm.size().y, " x ", bm.size().z, " / ", bmm.size().x, " x ", bmm.size().y,
          " x ", bmm.size().z);
  CHECK(bmm.lo.y == doctest::Approx(0.0).epsilon(1e-5));
  for (int axis = 0; axis < 3; ++axis) CHECK(std::abs(bm.size()[axis] - bmm.size()[axis]) < 0.03 * bm.size()[axis] + 0.003);
  const Box gm = box_of(nf::io::read_hair(work_m / "export" / "fur.hair").points), gmm = box_of(nf::io::read_hair(work_mm / "export" / "fur.hair").points);
  for (int axis = 0; axis < 3; ++axis) CHECK(std::abs(gm.size()[axis] - gmm.size()[axis]) < 0.1 * gm.size()[axis] + 0.01);
  fs::remove_all(root);
}
