#include "engine/pipeline/frames_stage.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/core/log.hpp"
#include "engine/fur/roots.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/geometry/tangent_field.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/npz.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/pipeline/defur_stage.hpp"
#include "engine/pipeline/knowledge_stage.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr int kStageVersion = 1;

double angle_deg(glm::vec3 a, glm::vec3 b) {
  const float la = glm::length(a), lb = glm::length(b);
  if (!(la > 0 && lb > 0)) return 0;
  return std::acos(std::clamp(double(glm::dot(a, b) / (la * lb)), -1.0, 1.0)) * 180.0 / M_PI;
}

// How well the field (and, for comparison, the knowledge's guide alone) points the way the
// ground-truth strands grow: each strand's root direction (root to its 4th point), projected onto
// the nearest face's plane, against that face's tangent.
json growth_agreement(const StageContext& c, const geometry::Mesh& bald, const geometry::TangentField& field,
                      const std::vector<glm::vec3>& guides) {
  const std::optional<io::GroundTruth> gt = io::find_ground_truth(c.scene_dir);
  if (!gt || !fs::exists(gt->strands())) return json();
  const io::StrandSet strands = io::read_hair(gt->strands());
  std::vector<float> centroids(3 * bald.triangle_count());
  for (std::size_t f = 0; f < bald.triangle_count(); ++f) {
    const glm::vec3 m = (bald.position(bald.triangles[3 * f]) + bald.position(bald.triangles[3 * f + 1]) + bald.position(bald.triangles[3 * f + 2])) / 3.f;
    for (int a = 0; a < 3; ++a) centroids[3 * f + std::size_t(a)] = m[a];
  }
  const geometry::PointIndex index(centroids);
  const std::uint32_t n = strands.strand_count(), step = std::max(1u, n / 20000);
  double field_sum = 0, guide_sum = 0;
  std::uint64_t count = 0, field_within_30 = 0, guide_count = 0;
  for (std::uint32_t s = 0; s < n; s += step) {
    if (strands.points_in(s) < 2) continue;
    const std::size_t p0 = strands.offsets[s], p1 = p0 + std::min<std::size_t>(3, strands.points_in(s) - 1);
    const glm::vec3 root(strands.points[3 * p0], strands.points[3 * p0 + 1], strands.points[3 * p0 + 2]);
    const glm::vec3 tip(strands.points[3 * p1], strands.points[3 * p1 + 1], strands.points[3 * p1 + 2]);
    const float q[3]{root.x, root.y, root.z};
    const std::uint32_t f = index.nearest(q).first;
    const glm::vec3 nrm = field.normal[f];
    glm::vec3 d = tip - root;
    d -= glm::dot(d, nrm) * nrm;
    if (!(glm::length(d) > 0) || !(glm::length(field.tangent[f]) > 0)) continue;
    const double a = angle_deg(field.tangent[f], d);
    field_sum += a, field_within_30 += a <= 30.0, ++count;
    glm::vec3 g = guides[f] - glm::dot(guides[f], nrm) * nrm;
    if (glm::length(g) > 0) guide_sum += angle_deg(g, d), ++guide_count;
  }
  json out{{"reference", "gt/strands.hair"}, {"strands_compared", count}};
  if (count) out["field_mean_angle_deg"] = field_sum / double(count), out["field_within_30_deg"] = double(field_within_30) / double(count);
  if (guide_count) out["guide_mean_angle_deg"] = guide_sum / double(guide_count);
  if (count) log::info("frames: the field is ", field_sum / double(count), " degrees from the ground truth's growth on average");
  return out;
}

}  // namespace

std::vector<fs::path> FramesStage::inputs(const StageContext& c) const {
  const DefurOutputs d = defur_outputs(c.work);
  std::vector<fs::path> files{d.bald(), d.vertex_fur(), knowledge_outputs(c.work).scale()};
  if (const auto gt = io::find_ground_truth(c.scene_dir))
    if (fs::exists(gt->strands())) files.push_back(gt->strands());
  return files;
}

json FramesStage::parameters(const StageContext& c) const {
  return key_of(c, kStageVersion);
}

json FramesStage::run(StageContext& c, const fs::path& out_dir, const fs::path&) {
  const FramesSettings s = settings_of(c);
  const FramesOutputs out{out_dir};
  const DefurOutputs d = defur_outputs(c.work);
  const Stopwatch t_all;
  json seconds = json::object();

  Stopwatch t;
  const geometry::Mesh bald = io::read_mesh(d.bald());
  const defur::VertexFur fur = defur::read_vertex_fur(d.vertex_fur(), bald.vertex_count());
  const double cm = read_metric_scale(knowledge_outputs(c.work));
  seconds["read"] = t.seconds();

  // Guides: the growing vertices' mean direction on faces that grow fur.
  t.restart();
  const std::vector<std::uint8_t> growing = fur::fur_faces(bald, fur);
  const std::vector<glm::vec3> guides = s.guide ? fur::face_growth_guides(bald, fur) : std::vector<glm::vec3>(bald.triangle_count(), glm::vec3(0.f));
  geometry::TangentFieldOptions options;
  options.smoothing_length = s.smoothing_cm / cm;
  const geometry::TangentField field = geometry::smooth_tangent_field(bald, guides, options);
  seconds["field"] = t.seconds();
  const geometry::FieldSmoothness smooth = geometry::field_smoothness(bald, field.tangent);
  // The guides alone (projected, normalised), for comparison: what the solve smooths.
  std::vector<glm::vec3> projected(guides.size(), glm::vec3(0.f));
  for (std::size_t f = 0; f < guides.size(); ++f) {
    const glm::vec3 p = guides[f] - glm::dot(guides[f], field.normal[f]) * field.normal[f];
    projected[f] = glm::length(p) > 1e-6f ? glm::normalize(p) : field.tangent[f];
  }
  const geometry::FieldSmoothness guide_smooth = geometry::field_smoothness(bald, projected);
  log::info("frames: tangent field on ", bald.triangle_count(), " faces (", field.guided_faces, " guided) in ", field.solve_seconds,
            " s; neighbours differ by ", smooth.mean_angle_deg, " degrees on average");

  t.restart();
  const std::uint64_t nf = bald.triangle_count();
  io::NpyWrite tangent{"tangent", {nf, 3}, "<f4", {}}, bitangent{"bitangent", {nf, 3}, "<f4", {}}, normal{"normal", {nf, 3}, "<f4", {}};
  for (std::size_t f = 0; f < nf; ++f) {
    const glm::vec3 b = glm::cross(field.normal[f], field.tangent[f]);
    for (int a = 0; a < 3; ++a)
      tangent.values.push_back(field.tangent[f][a]), bitangent.values.push_back(b[a]), normal.values.push_back(field.normal[f][a]);
  }
  io::write_npz(out.frames(), {tangent, bitangent, normal});
  seconds["write_frames"] = t.seconds();

  t.restart();
  const fur::Roots roots = fur::sample_roots(bald, {field.tangent, field.normal}, fur, std::uint64_t(s.roots), s.seed);
  fur::write_roots(out.roots(), roots);
  seconds["roots"] = t.seconds();
  if (roots.size() == 0)
    log::warn("frames: no region of the knowledge grows fur on M_bald, so there are no roots: the fur stage has nothing to grow");

  const double fur_area = fur::fur_area(bald, fur);
  json summary{{"faces", nf},
               {"guided_faces", field.guided_faces},
               {"filled_faces", field.filled_faces},
               {"fur_faces", std::count(growing.begin(), growing.end(), std::uint8_t(1))},
               {"fur_area_cm2", fur_area * cm * cm},
               {"smoothing_cm", s.smoothing_cm},
               {"smoothness", geometry::to_json(smooth)},
               {"guide_smoothness", geometry::to_json(guide_smooth)},
               {"roots", roots.size()},
               {"seconds", seconds}};
  const json gt = growth_agreement(c, bald, field, guides);
  if (!gt.is_null()) summary["ground_truth"] = gt;
  summary["seconds_total"] = t_all.seconds();
  write_file_atomic(out.metrics(), summary.dump(2) + "\n");
  return summary;
}

const SettingsSchema<FramesSettings>& frames_settings() {
  using F = FramesSettings;
  static const SettingsSchema<F> schema = [] {
    SettingsSchema<F> s("frames", [](const std::string&) { return F{}; });
    s.add("smoothing_cm", [](F& f) -> auto& { return f.smoothing_cm; }, 0.01, 1000,
          "how far (cm) a region's growth direction spreads before its neighbours' pull wins")
        .add("guide", [](F& f) -> auto& { return f.guide; }, 0, 1,
             "align the field with the knowledge's growth directions (else: the smoothest field)")
        .add("roots", [](F& f) -> auto& { return f.roots; }, 0, 1e8, "fur roots written to roots.npz")
        .add("seed", [](F& f) -> auto& { return f.seed; }, 0, 4294967295.0, "root sampling seed");
    return s;
  }();
  return schema;
}

}  // namespace nf::pipeline
