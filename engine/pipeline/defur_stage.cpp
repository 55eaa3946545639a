#include "engine/pipeline/defur_stage.hpp"

#include <algorithm>
#include <cmath>

#include "engine/body/mane_labels.hpp"
#include "engine/body/region_transfer.hpp"
#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/core/log.hpp"
#include "engine/defur/defur_surface.hpp"
#include "engine/defur/nonbald_masks.hpp"
#include "engine/defur/sdf_file.hpp"
#include "engine/defur/vertex_fur.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/view_names.hpp"
#include "engine/metrics/surface_metrics.hpp"
#include "engine/pipeline/body_stage.hpp"
#include "engine/pipeline/knowledge_stage.hpp"
#include "engine/pipeline/neus_stage.hpp"
#include "engine/pipeline/preview_views.hpp"
#include "engine/synth/preview.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr int kStageVersion = 4;  // 2: the knowledge's mane labelled on M_NeuS and M_bald; 3: pads only where M_bald faces down; 4: M_bald labelled from the template's finer build

// The bald body's grid for the penetration loss: spacing half the fur's median thickness, so a
// strand point sunk by a fraction of the fur layer is resolved, within 64..256 samples along the
// longest side (128 when nothing has thickness).
int sdf_resolution(const geometry::Mesh& bald, const knowledge::Knowledge& knowledge, double cm_per_unit) {
  std::vector<float> thickness;  // per vertex of M_bald, through its regions
  for (std::int32_t r : bald.regions)
    if (knowledge.has(body::Region(r)) && knowledge.at(body::Region(r)).thickness_cm > 0)
      thickness.push_back(float(knowledge.at(body::Region(r)).thickness_cm / cm_per_unit));
  const double longest = double(geometry::mesh_bounds(bald).longest());
  if (thickness.empty()) return 128;
  std::nth_element(thickness.begin(), thickness.begin() + std::ptrdiff_t(thickness.size() / 2), thickness.end());
  const double spacing = 0.5 * double(thickness[thickness.size() / 2]);
  return int(std::clamp(longest / spacing + 1.0, 64.0, 256.0));
}

// The previews: M_bald in its regions' colours, and a pale blue where M_NeuS's fur layer covers
// the view without M_bald behind it.
std::vector<fs::path> write_previews(StageContext& c, const geometry::Mesh& bald, const geometry::Mesh& outer, int count,
                                     const fs::path& dir) {
  const std::vector<std::uint32_t> views = preview_views(c.scene, count);
  if (views.empty()) return {};
  const std::vector<io::Image> images = synth::render_region_images(bald, c.scene, views);
  const std::vector<std::string> names = io::view_file_names(c.scene, views);
  fs::create_directories(dir);
  std::vector<fs::path> files;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const io::Camera& cam = c.scene.cameras[views[i]];
    const std::vector<float> d_outer = defur::camera_depth(c.gpu, outer, cam), d_bald = defur::camera_depth(c.gpu, bald, cam);
    io::Image image = images[i];
    for (std::size_t p = 0; p < d_outer.size(); ++p)
      if (std::isfinite(d_outer[p]) && !std::isfinite(d_bald[p]))
        for (std::uint32_t ch = 0; ch < 3; ++ch) image.pixels[3 * p + ch] = std::array<float, 3>{0.62f, 0.78f, 0.95f}[ch];
    files.push_back(dir / (names[i] + ".png"));
    io::write_png(files.back(), image);
  }
  return files;
}

json ground_truth_metrics(const StageContext& c, const geometry::Mesh& bald, const geometry::Mesh& outer) {
  const std::optional<io::GroundTruth> gt = io::find_ground_truth(c.scene_dir);
  if (!gt || !fs::exists(gt->bald())) return json();
  const geometry::Mesh reference = io::read_mesh(gt->bald());
  const double diagonal_mm = double(geometry::mesh_bounds(reference).diagonal()) * gt->cm_per_unit * 10.0;
  const auto against = [&](const geometry::Mesh& m) {
    json j = metrics::to_json(metrics::surface_metrics(m, reference, gt->cm_per_unit));
    j["chamfer_percent_of_diagonal"] = 100.0 * j["chamfer_mm"]["mean"].get<double>() / diagonal_mm;
    return j;
  };
  json out{{"reference", "gt/bald.ply"}, {"bald", against(bald)}, {"outer", against(outer)}, {"diagonal_mm", diagonal_mm}};
  if (!bald.regions.empty() && !reference.regions.empty()) {
    out["regions"] = body::to_json(body::region_accuracy(bald, reference));
    out["regions_outer"] = body::to_json(body::region_accuracy(outer, reference));  // with the mane, when labelled here
  }
  log::info("defur: chamfer to gt/bald.ply: M_bald ", out["bald"]["chamfer_mm"]["mean"].get<double>(), " mm, M_NeuS ",
            out["outer"]["chamfer_mm"]["mean"].get<double>(), " mm");
  return out;
}

// When the knowledge grows a mane, the fitted body's neck and the back of its head become mane on
// `surface` (body::label_mane): the template has no mane of its own.
body::ManeLabelling label_mane_from_fit(const body::BodyModel& model, const body::BodyFit& fit, const geometry::Mesh& fitted,
                                        geometry::Mesh& surface, const std::string& source) {
  const std::optional<body::HeadAxis> head = body::head_axis(model, body::fitted_joints(model, fit));
  if (!head) log::warn("defur: the body model has no 'head' and 'muzzle' joints: only its neck becomes the mane");
  return body::label_mane(surface, fitted, head, source);
}

}  // namespace

std::vector<fs::path> DefurStage::inputs(const StageContext& c) const {
  const BodyOutputs body = body_outputs(c.work);
  const KnowledgeOutputs k = knowledge_outputs(c.work);
  std::vector<fs::path> files{body.outer_regions(), body.fitted(), body.fit_state(), k.knowledge(), k.directions_world(), k.scale()};
  const BodySettings b = resolve_settings(body_settings(), c);
  if (!b.model.empty()) files.push_back(b.model);
  if (const auto gt = io::find_ground_truth(c.scene_dir))
    if (fs::exists(gt->bald())) files.push_back(gt->bald());
  return files;
}

json DefurStage::parameters(const StageContext& c) const {
  json key = key_of(c, kStageVersion);
  key["body"] = settings_values(body_settings(), c);  // the re-fit's schedule
  key["cameras"] = cameras_json(c.scene);
  return key;
}

json DefurStage::run(StageContext& c, const fs::path& out_dir, const fs::path&) {
  const DefurSettings s = settings_of(c);
  const DefurOutputs out{out_dir};
  const BodyOutputs body_files = body_outputs(c.work);
  const KnowledgeOutputs k_files = knowledge_outputs(c.work);
  const Stopwatch t_all;
  json seconds = json::object();

  Stopwatch t;
  geometry::Mesh outer = io::read_mesh(body_files.outer_regions());
  const knowledge::Knowledge knowledge = knowledge::read_knowledge(k_files.knowledge());
  const double cm = read_metric_scale(k_files);
  seconds["read"] = t.seconds();

  t.restart();
  const BodySettings b = resolve_settings(body_settings(), c);
  const body::BodyModel model = body_model_of(b);
  const body::BodyFit fit = read_body_fit(body_files, model);
  const bool has_mane = knowledge.grows_fur(body::Region::mane);
  json mane;
  if (has_mane) {
    const body::ManeLabelling m = label_mane_from_fit(model, fit, io::read_mesh(body_files.fitted()), outer, body_files.fitted().string());
    log::info("defur: the knowledge grows a mane: ", m.vertices, " vertices of M_NeuS (", 100.0 * m.area_share,
              " % of its area) on the fitted neck and the back of its head");
    mane = {{"outer", body::to_json(m)}};
  }
  seconds["fit_and_mane"] = t.seconds();

  defur::DefurOptions options;
  options.resolution = s.resolution, options.target_faces = std::uint64_t(s.faces);
  options.max_hole_edges = std::uint32_t(s.max_hole_edges), options.cm_per_unit = cm;
  options.thickness_smoothing = s.thickness_smoothing;
  defur::DefurResult result = defur::defur_surface(c.gpu, outer, knowledge, options, body_files.outer_regions().string());
  for (const auto& [step, sec] : result.seconds.items()) seconds[step] = sec;
  geometry::Mesh& bald = result.bald;
  for (const defur::RegionDepth& r : result.regions)
    if (r.vanishes)
      log::warn("defur: region '", body::region_name(r.region), "' has fur ", r.thickness * cm, " cm thick but is only ", r.depth * cm,
                " cm deep: M_bald loses it");
  log::info("defur: M_bald has ", bald.triangle_count(), " faces (", result.extracted_faces, " extracted on a ",
            result.grid.dims.x, "x", result.grid.dims.y, "x", result.grid.dims.z, " grid)");

  // Regions on M_bald: the body re-fitted to it (its labels are the template's, not M_NeuS's
  // nearest, which would drift inwards across thin parts).
  t.restart();
  json refit_summary;
  if (s.refit) {
    const body::BodyFit refit = body::refit_body(model, bald, fit, b.fit, out.bald().string());
    bald.regions = body::nearest_regions(bald, body::region_carrier(model, refit.fitted));
    if (has_mane) mane["bald"] = body::to_json(label_mane_from_fit(model, refit, refit.fitted, bald, out.refit().string()));
    io::write_mesh_ply(out.refit(), refit.fitted);
    refit_summary = {{"chamfer_mean", refit.chamfer_mean}, {"relative_chamfer", refit.relative_chamfer},
                     {"low_confidence", refit.low_confidence}};
  } else {
    bald.regions = body::nearest_regions(bald, outer);
  }
  if (bald.normals.empty()) geometry::compute_vertex_normals(bald);
  body::pads_face_down(bald, glm::dvec3(fit.animal_to_world[1]));
  seconds["refit"] = t.seconds();

  t.restart();
  const defur::VertexFur fur = defur::vertex_fur(bald, knowledge, read_directions_world(k_files), cm, s.knowledge_smoothing);
  io::write_mesh_ply(out.bald(), bald);
  defur::write_vertex_fur(out.vertex_fur(), fur);
  std::size_t bald_vertices = 0;
  for (std::size_t v = 0; v < fur.size(); ++v) bald_vertices += !fur.grows(v);
  seconds["vertex_knowledge"] = t.seconds();

  t.restart();
  const defur::SdfFile bald_sdf =
      defur::bald_body_sdf(bald, s.sdf_resolution > 0 ? s.sdf_resolution : sdf_resolution(bald, knowledge, cm), out.bald().string());
  defur::write_sdf_file(out.bald_sdf(), bald_sdf);
  seconds["bald_sdf"] = t.seconds();

  t.restart();
  json masks_summary;
  if (s.masks && !c.scene.cameras.empty()) {
    std::vector<std::uint32_t> views(c.scene.cameras.size());
    for (std::uint32_t v = 0; v < views.size(); ++v) views[v] = v;
    defur::MaskStats stats;
    const std::vector<io::Image> masks = defur::nonbald_masks(c.gpu, outer, knowledge, c.scene, views, &stats);
    const std::vector<std::string> names = io::view_file_names(c.scene, views);
    fs::create_directories(out.masks());
    for (std::size_t i = 0; i < masks.size(); ++i) io::write_png(out.masks() / (names[i] + ".png"), masks[i]);
    masks_summary = {{"views", masks.size()}, {"animal_pixels", stats.animal}, {"fur_pixels", stats.fur},
                     {"fur_fraction_of_animal", stats.animal ? double(stats.fur) / double(stats.animal) : 0.0}};
  }
  seconds["masks"] = t.seconds();

  t.restart();
  const std::vector<fs::path> previews = write_previews(c, bald, outer, s.preview_views, out.previews());
  seconds["previews"] = t.seconds();

  json summary = defur::to_json(result);
  summary["seconds"] = seconds;
  summary["seconds_total"] = t_all.seconds();
  summary["cm_per_unit"] = cm;
  summary["refit"] = refit_summary;
  summary["bald_vertices"] = bald_vertices;
  summary["bald_sdf"] = {{"dims", {bald_sdf.grid.dims.x, bald_sdf.grid.dims.y, bald_sdf.grid.dims.z}},
                         {"spacing", bald_sdf.grid.voxel}, {"band", bald_sdf.band}};
  summary["masks"] = masks_summary;
  if (!mane.is_null()) summary["mane"] = mane;
  summary["previews"] = previews.size();
  const json gt = ground_truth_metrics(c, bald, outer);
  if (!gt.is_null()) summary["ground_truth"] = gt;
  write_file_atomic(out.metrics(), summary.dump(2) + "\n");
  return summary;
}

const SettingsSchema<DefurSettings>& defur_settings() {
  using D = DefurSettings;
  static const SettingsSchema<D> schema = [] {
    SettingsSchema<D> s("defur", [](const std::string&) { return D{}; });
    s.add("resolution", [](D& d) -> auto& { return d.resolution; }, 16, 1024, "SDF grid samples along M_NeuS's longest side")
        .add("faces", [](D& d) -> auto& { return d.faces; }, 1000, 1e7, "M_bald's face budget (a coarser extraction is kept)")
        .add("thickness_smoothing", [](D& d) -> auto& { return d.thickness_smoothing; }, 0, 10000,
             "Laplacian iterations over M_NeuS smoothing the thickness across region borders")
        .add("knowledge_smoothing", [](D& d) -> auto& { return d.knowledge_smoothing; }, 0, 10000,
             "Laplacian iterations over M_bald smoothing length and direction across region borders")
        .add("max_hole_edges", [](D& d) -> auto& { return d.max_hole_edges; }, 0, 100000, "longest boundary loop filled")
        .add("sdf_resolution", [](D& d) -> auto& { return d.sdf_resolution; }, 0, 1024,
             "bald_sdf samples along the longest side; 0: from the fur's thickness (64..256)")
        .add("refit", [](D& d) -> auto& { return d.refit; }, 0, 1, "re-fit the body to M_bald for its regions (else M_NeuS's nearest)")
        .add("masks", [](D& d) -> auto& { return d.masks; }, 0, 1, "write the non-bald masks of every camera")
        .add("preview_views", [](D& d) -> auto& { return d.preview_views; }, 0, 16, "previews of M_bald over M_NeuS")
        .check([](const D& d) {
          if (d.sdf_resolution != 0 && d.sdf_resolution < 16)
            throw UsageError("sdf_resolution must be 0 (from the fur's thickness) or at least 16, got " + std::to_string(d.sdf_resolution));
        });
    return s;
  }();
  return schema;
}

}  // namespace nf::pipeline
