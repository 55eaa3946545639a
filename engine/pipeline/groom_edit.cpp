#include "engine/pipeline/groom_edit.hpp"

#include <cmath>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/core/log.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/defur/vertex_fur.hpp"
#include "engine/export/region_edits.hpp"
#include "engine/fur/fur_model_file.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/npz.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/pipeline/defur_stage.hpp"
#include "engine/pipeline/export_stage.hpp"
#include "engine/pipeline/frames_stage.hpp"
#include "engine/pipeline/fur_stage.hpp"
#include "engine/pipeline/knowledge_stage.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;
json run_edit(gpu::Context& context, const EditOptions& o) {
  const Stopwatch t_all;
  if (o.out.empty()) throw UsageError("--out: an output folder is needed");
  refuse_output_inside(o.out, o.work, "--out", "WORK");
  require_export(o.work);
  const ExportOptions export_options = preview_options(o.quality, o.formats);
  exporter::GroomEdits edits = exporter::GroomEdits::parse(o.sets, o.shave);
  edits.strands = o.strands;
  require_folder_or_absent(o.out, "--out");

  const geometry::Mesh bald = io::read_mesh(defur_outputs(o.work).bald());
  const defur::VertexFur vertex_fur = defur::read_vertex_fur(defur_outputs(o.work).vertex_fur(), bald.vertex_count());
  const fur::FaceFrames frames = read_face_frames(frames_outputs(o.work).frames(), bald.triangle_count());
  const knowledge::Knowledge knowledge = knowledge::read_knowledge(knowledge_outputs(o.work).knowledge());
  std::size_t before = 0;
  const fur::Roots roots = [&] {  // the roots before the edits are dropped once edited
    const fur::Roots base = edits.strands ? fur::sample_roots(bald, frames, vertex_fur, *edits.strands, o.seed + 11)
                                          : fur::read_roots(groom_roots_file(o.work));
    before = base.size();
    return exporter::edit_roots(base, edits, knowledge, bald, frames, vertex_fur, o.seed + 101);
  }();
  OutputFolder folder(o.out, "edit");

  // Inference from the trained field: the same code and chunks as the fur stage, so strands of
  // unedited roots come out bit-identical.
  Stopwatch t;
  fur::FurModel model = fur::load_fur_model(context, fur_outputs(o.work).model());
  {  // A length the user sets is the strands' length: the factor learned from the photos is dropped there.
    fur::LengthFactors factors = model.field->length_factors();
    for (std::size_t r = 0; r < factors.size() && r < edits.regions.size(); ++r)
      if (edits.regions[r].length_cm) factors[r] = 1.f;
    model.field->set_length_factors(std::move(factors));
  }
  const auto n = std::uint32_t(roots.size());
  std::vector<std::uint32_t> ids(n);
  for (std::uint32_t i = 0; i < n; ++i) ids[i] = i;
  io::write_uniform_hair(folder.claim(SceneGroom{o.out}.strands().filename().string()), n, fur::kStrandPoints, [&](const auto& write) {
    model.field->infer(roots, ids, 65536, [&](std::size_t, std::uint32_t, const std::vector<float>& points, const std::vector<float>&) {
      stop_if_interrupted("edit");  // the partial file is removed
      write(std::span<const float>(points));
    });
  });
  io::NpyWrite regions{"region", {n}, "<i4", {}};
  for (std::uint32_t i = 0; i < n; ++i) regions.values.push_back(roots.region[i]);
  io::write_npz(folder.claim(SceneGroom{o.out}.regions().filename().string()), {regions});
  fur::write_roots(folder.claim(SceneGroom{o.out}.roots().filename().string()), roots);
  const double infer_seconds = t.seconds();
  log::info("edit: ", n, " strands inferred in ", infer_seconds, " s (", before, " before the edits)");

  const GroomInput groom = read_groom(SceneGroom{o.out}.strands(), SceneGroom{o.out}.regions(), SceneGroom{o.out}.roots(), o.work);
  ExportScene scene;
  scene.bald_world = &bald;
  scene.body_colors = read_body_colors(o.work, bald.vertex_count());
  scene.frame = read_export_frame(export_outputs(o.work));
  const io::Skeleton skeleton = read_export_skeleton(o.work, bald);
  scene.skeleton = &skeleton;
  scene.hair_diameter_mm = exporter::region_hair_diameter_mm(knowledge, edits);
  scene.title = "nf_gpu groom, edited";
  const json exported = write_export(folder, groom, scene, export_options);
  json diameters = json::object();
  for (int r = 0; r < body::kRegionCount; ++r) diameters[std::string(body::kRegionNames[std::size_t(r)])] = scene.hair_diameter_mm[std::size_t(r)];
  json record{{"work", fs::absolute(o.work).string()},
              {"edits", edits.to_json()},
              {"seed", o.seed},
              {"strands", {{"before", before}, {"after", n}}},
              {"hair_diameter_mm", diameters},
              {"seconds", {{"inference", infer_seconds}, {"export", exported["seconds_total"]}, {"total", t_all.seconds()}}},
              {"export", exported}};
  write_file_atomic(folder.claim("edit.json"), record.dump(2) + "\n");
  folder.finish();
  return record;
}

}  // namespace nf::pipeline
