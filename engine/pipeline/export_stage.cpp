#include "engine/pipeline/export_stage.hpp"

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/parallel.hpp"
#include "engine/export/body_rig.hpp"
#include "engine/export/region_edits.hpp"
#include "engine/fur/roots.hpp"
#include "engine/fur/strand_colors.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/npz.hpp"
#include "engine/io/view_split.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/pipeline/body_stage.hpp"
#include "engine/pipeline/defur_stage.hpp"
#include "engine/pipeline/export_files.hpp"
#include "engine/pipeline/fur_stage.hpp"
#include "engine/pipeline/knowledge_stage.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;
namespace {

constexpr int kStageVersion = 4;  // 2: the strands' colours; 3: index.html; 4: the body's colours

ExportOptions export_preset(const std::string& quality) {
  ExportOptions o;
  if (quality == "draft") o.turntable_frames = 8, o.compare_views = 2, o.preview_size = 512, o.preview_strands = 20000;
  else if (quality == "paper") o.turntable_frames = 24, o.compare_views = 5, o.preview_size = 768, o.preview_strands = 60000;
  return o;
}

}  // namespace

const SettingsSchema<ExportOptions>& export_settings() {
  using E = ExportOptions;
  static const SettingsSchema<E> schema = [] {
    SettingsSchema<E> s("export", export_preset);
    s.text("formats", [](E& e) -> auto& { return e.formats; }, {}, "groom files, comma-separated: usda, hair, ply, obj")
        .add("tip_width", [](E& e) -> auto& { return e.tip_width; }, 0, 1, "a strand's width at its tip as a share of the root's")
        .add("width_scale", [](E& e) -> auto& { return e.width_scale; }, 1e-3, 1e4,
             "a strand's width at the root as a multiple of the knowledge's hair diameter (a guide strand drawn for many hairs may be wider)")
        .add("turntable_frames", [](E& e) -> auto& { return e.turntable_frames; }, 0, 360, "preview frames around the animal (0: none)")
        .add("compare_views", [](E& e) -> auto& { return e.compare_views; }, 0, 1000, "held-out photos shown beside the groom's render (0: none)")
        .add("preview_size", [](E& e) -> auto& { return e.preview_size; }, 16, 8192, "previews' longer side in pixels")
        .add("preview_strands", [](E& e) -> auto& { return e.preview_strands; }, 0, 1e7, "strands drawn in the previews (an even subset)")
        .check([](const E& e) { (void)e.format_list(); });
    return s;
  }();
  return schema;
}

exporter::ExportFrame read_export_frame(const ExportOutputs& o) {
  const json j = io::read_json_file(o.record());
  const io::JsonField frame = io::JsonField(j, o.record().string()).at("frame");
  exporter::ExportFrame f;
  f.world_to_export = io::matrix_rows(frame.at("world_to_export"));
  const io::JsonField m = frame.at("metres_per_scene_unit");
  if (!(m.number() > 0)) m.fail("expected a positive number");
  f.metres_per_unit = m.number();
  return f;
}

void require_export(const fs::path& work) {
  if (!fs::is_directory(work))
    throw InputError("--work " + work.string() + ": " + (fs::exists(work) ? "is a file, not" : "no such folder; it should be") +
                     " a WORK folder that nf_gpu reconstruct wrote");
  if (!fs::exists(export_outputs(work).record()) || !fs::exists(export_outputs(work).body()))
    throw InputError(work.string() + ": no finished export stage (export/export.json, export/body.glb); run nf_gpu reconstruct to the end first");
}

io::Skeleton read_export_skeleton(const fs::path& work, const geometry::Mesh& bald) {
  const fs::path glb = export_outputs(work).body();
  io::Skeleton s = io::read_skeleton_gltf(glb);
  if (s.skin_weights.size() != io::kJointInfluences * bald.vertex_count())
    throw InputError(glb.string() + ": its skin has " + std::to_string(s.skin_weights.size() / io::kJointInfluences) +
                     " vertices but defur/bald.ply has " + std::to_string(bald.vertex_count()) + "; rerun the export stage");
  return s;
}

ExportOptions preview_options(const std::string& quality, const std::string& formats) {
  ExportOptions o = export_settings().resolve(quality, json::object());
  if (!formats.empty()) o.formats = formats;
  (void)o.format_list();
  o.compare_views = 0;  // the photos belong to the reconstruction, not to an edit or a pose
  return o;
}

namespace {

// The fur stage's colours for strands rooted at `roots` (see read_groom).
void attach_fur_colors(GroomInput& g, const fur::Roots& roots, const fs::path& work) {
  const FurOutputs f = fur_outputs(work);
  if (!fs::exists(f.colors())) return;  // a groom without colours (fur.color_controls=0, or an older fur stage)
  const fur::Roots colored = fur::read_roots(groom_roots_file(work));
  const fur::StrandColors stored = fur::read_strand_colors(f.colors(), colored.size());
  g.color_controls = stored.controls;
  const std::size_t per = std::size_t(g.color_controls) * 3;
  std::vector<float> positions;
  positions.reserve(3 * colored.size());
  for (const glm::vec3& p : colored.position) positions.insert(positions.end(), {p.x, p.y, p.z});
  const geometry::PointIndex index(positions);
  g.colors.resize(roots.size() * per);
  parallel_for(roots.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const float q[3] = {roots.position[i].x, roots.position[i].y, roots.position[i].z};
      const std::size_t from = std::size_t(index.nearest(q).first) * per;
      std::copy_n(&stored.rgb[from], per, &g.colors[i * per]);
    }
  });
}

// What index.html shows of the fur stage's metrics.json (on synth scenes, against the truth too).
std::vector<std::pair<std::string, std::string>> page_figures(const json& m) {
  std::vector<std::pair<std::string, std::string>> out;
  const auto fixed = [](double v, int digits) {
    char text[32];
    std::snprintf(text, sizeof text, "%.*f", digits, v);
    return std::string(text);
  };
  if (m.contains("selection") && m["selection"].contains("kept"))
    out.push_back({"groom kept", m["selection"]["kept"].get<std::string>() + " (of " + std::to_string(m.value("steps", 0)) + " steps)"});
  if (m.contains("held_out") && m["held_out"].contains("silhouette_iou"))
    out.push_back({"held-out photos: silhouette IoU, orientation error",
                   fixed(m["held_out"]["silhouette_iou"].get<double>(), 3) + ", " + fixed(m["held_out"].value("orientation_error_deg", 0.0), 1) + " degrees"});
  if (m.contains("groom") && m["groom"].contains("fscore")) {
    const json& g = m["groom"]["fscore"];
    const json& b = m.contains("baseline") && m["baseline"].contains("fscore") ? m["baseline"]["fscore"] : json::object();
    out.push_back({"against the true strands: F(2 cm, 20 deg) / F(2 mm, 20 deg)",
                   fixed(g.value("2cm_20deg", 0.0), 1) + " / " + fixed(g.value("2mm_20deg", 0.0), 1) + " (straight strands: " +
                       fixed(b.value("2cm_20deg", 0.0), 1) + " / " + fixed(b.value("2mm_20deg", 0.0), 1) + ")"});
  }
  if (m.contains("colors") && m["colors"].contains("strands_seen"))
    out.push_back({"strands a photo showed (the others take their neighbours' colours)", fixed(100.0 * m["colors"]["strands_seen"].get<double>(), 0) + " %"});
  if (m.contains("colors") && m["colors"].contains("ground_truth")) {
    const json& e = m["colors"]["ground_truth"];
    const auto mean = [&](const json& summary) { return summary.value("count", 0) > 0 ? fixed(summary["mean"].get<double>(), 1) : std::string("n/a"); };
    out.push_back({"colours against the true ones: Delta E seen / filled", mean(e["delta_e_seen"]) + " / " + mean(e["delta_e_unseen"])});
  }
  if (m.contains("seconds_total")) out.push_back({"fur stage", fixed(m["seconds_total"].get<double>(), 0) + " s"});
  return out;
}

}  // namespace

GroomInput read_groom(const fs::path& strands, const fs::path& regions, const fs::path& roots_file, const fs::path& work) {
  GroomInput g;
  g.strands = io::stream_hair_file(strands);
  const io::NpyArray region = io::read_npz_array(regions, "region");
  const fur::Roots roots = fur::read_roots(roots_file);
  const std::uint64_t n = g.strands.strands;
  if (region.values.size() != n)
    throw InputError(regions.string() + ": 'region' has " + std::to_string(region.values.size()) + " entries for the " + std::to_string(n) +
                     " strands of " + strands.string());
  if (roots.size() != n)
    throw InputError(roots_file.string() + ": " + std::to_string(roots.size()) + " roots for the " + std::to_string(n) + " strands of " +
                     strands.string() + "; rerun the fur stage");
  g.region.assign(region.values.begin(), region.values.end());
  g.root_face = roots.face;
  g.root_barycentric = roots.barycentric;
  attach_fur_colors(g, roots, work);
  return g;
}

std::vector<float> read_body_colors(const fs::path& work, std::uint64_t vertices) {
  const fs::path file = fur_outputs(work).body_colors();
  if (!fs::exists(file)) return {};  // fur.color_controls=0, or a fur stage made before body colours
  if (const std::size_t rows = io::read_npz_array(file, "seen").values.size(); rows != vertices) {
    log::warn(file.string(), ": colours for ", rows, " vertices, but the body has ", vertices, " (a fur stage on another body); the body stays grey");
    return {};
  }
  const fur::StrandColors c = fur::read_strand_colors(file, vertices);
  if (c.controls != 1) throw InputError(file.string() + ": 'rgb' should hold one colour per vertex, not " + std::to_string(c.controls) + "; rerun the fur stage");
  return c.rgb;
}

std::vector<fs::path> ExportStage::inputs(const StageContext& c) const {
  const FurOutputs f = fur_outputs(c.work);
  const BodyOutputs b = body_outputs(c.work);
  std::vector<fs::path> files{f.strands(), f.regions(), f.metrics(), defur_outputs(c.work).bald(), b.fit_state(), b.animal_frame(),
                              knowledge_outputs(c.work).knowledge(), knowledge_outputs(c.work).scale()};
  if (fs::exists(f.roots())) files.push_back(f.roots());
  if (fs::exists(f.colors())) files.push_back(f.colors());
  if (fs::exists(f.body_colors())) files.push_back(f.body_colors());
  const std::string model = resolve_settings(body_settings(), c).model;
  if (!model.empty()) files.push_back(model);
  return files;
}

json ExportStage::parameters(const StageContext& c) const {
  json key = key_of(c, kStageVersion);
  key["body_model"] = resolve_settings(body_settings(), c).model;
  key["hold_out_every"] = resolve_settings(fur_settings(), c).hold_out_every;
  return key;
}

json ExportStage::run(StageContext& c, const fs::path& out_dir, const fs::path&) {
  const ExportOptions o = resolve_settings(export_settings(), c);
  const body::BodyModel model = body_model_of(resolve_settings(body_settings(), c));
  const BodyOutputs b = body_outputs(c.work);
  const body::BodyFit fit = read_body_fit(b, model);
  const geometry::Mesh bald = io::read_mesh(defur_outputs(c.work).bald());
  const double cm = read_metric_scale(knowledge_outputs(c.work));
  const knowledge::Knowledge knowledge = knowledge::read_knowledge(knowledge_outputs(c.work).knowledge());
  const FurOutputs f = fur_outputs(c.work);
  const GroomInput groom = read_groom(f.strands(), f.regions(), groom_roots_file(c.work), c.work);

  ExportScene scene;
  scene.bald_world = &bald;
  scene.body_colors = read_body_colors(c.work, bald.vertex_count());
  scene.frame = exporter::export_frame(read_animal_to_world(b), cm, bald);
  const io::Skeleton skeleton = exporter::transfer_rig(model, fit, bald, scene.frame);
  scene.skeleton = &skeleton;
  scene.hair_diameter_mm = exporter::region_hair_diameter_mm(knowledge, {});
  scene.scene = &c.scene;
  const int every = resolve_settings(fur_settings(), c).hold_out_every;
  for (std::uint32_t v = 0; v < c.scene.cameras.size(); ++v)
    if (io::is_held_out(v, every)) scene.compare_cameras.push_back(v);
  if (scene.compare_cameras.empty() && !c.scene.cameras.empty()) scene.compare_cameras.push_back(0);
  fs::path scene_name = fs::absolute(c.scene_dir).lexically_normal();
  if (scene_name.filename().empty()) scene_name = scene_name.parent_path();  // `--scene cat/`
  scene.title = "nf_gpu groom: " + scene_name.filename().string();
  scene.figures = page_figures(io::read_json_file(f.metrics()));
  OutputFolder folder(out_dir, "export");
  json record = write_export(folder, groom, scene, o);
  log::info("export: ", groom.strands.strands, " strands and the rigged body (", skeleton.joint_count(), " joints)");
  return record;
}

}  // namespace nf::pipeline
