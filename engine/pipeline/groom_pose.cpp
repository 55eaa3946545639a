#include "engine/pipeline/groom_pose.hpp"

#include <cmath>
#include <cstdio>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/core/text.hpp"
#include "engine/export/region_edits.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/io/mesh.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/pipeline/defur_stage.hpp"
#include "engine/pipeline/export_stage.hpp"
#include "engine/pipeline/fur_stage.hpp"
#include "engine/pipeline/knowledge_stage.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;

json run_pose(const PoseOptions& o) {
  const Stopwatch t_all;
  if (o.out.empty()) throw UsageError("--out: an output folder is needed");
  refuse_output_inside(o.out, o.work, "--out", "WORK");
  if (!o.groom.empty()) {
    refuse_output_inside(o.out, o.groom, "--out", "--groom");
    if (!fs::exists(o.groom / "edit.json") || !fs::exists(SceneGroom{o.groom}.strands()))
      throw InputError("--groom " + o.groom.string() + ": " + (fs::is_directory(o.groom) ? "holds no edit (edit.json and " +
                       SceneGroom{o.groom}.strands().filename().string() + ")" : std::string("no such folder")) +
                       "; it should be an output folder of nf_gpu edit");
  }
  require_export(o.work);
  const ExportOptions export_options = preview_options(o.quality, o.formats);
  require_folder_or_absent(o.out, "--out");
  const geometry::Mesh bald = io::read_mesh(defur_outputs(o.work).bald());
  const io::Skeleton skeleton = read_export_skeleton(o.work, bald);

  // joint.NAME=rx,ry,rz: a rotation vector in degrees.
  std::vector<glm::vec3> rotations(skeleton.joint_count(), glm::vec3(0.f));
  json asked = json::object();
  for (const std::string& set : o.sets) {
    const std::size_t eq = set.find('=');
    if (set.rfind("joint.", 0) != 0 || eq == std::string::npos)
      throw UsageError("--set " + set + ": expected joint.NAME=rx,ry,rz (a rotation vector in degrees)");
    const std::string name = set.substr(6, eq - 6);
    std::size_t j = 0;
    while (j < skeleton.joint_count() && skeleton.joint_names[j] != name) ++j;
    if (j == skeleton.joint_count())
      throw UsageError("--set " + set + ": the skeleton has no joint '" + name + "'" + did_you_mean(name, skeleton.joint_names) +
                       " (joints: " + join(skeleton.joint_names) + ")");
    glm::vec3 degrees;
    char tail = 0;
    if (std::sscanf(set.c_str() + eq + 1, "%f,%f,%f%c", &degrees.x, &degrees.y, &degrees.z, &tail) != 3 || !std::isfinite(glm::length(degrees)))
      throw UsageError("--set " + set + ": expected three numbers rx,ry,rz (degrees)");
    rotations[j] = glm::radians(degrees);
    asked[name] = {degrees.x, degrees.y, degrees.z};
  }

  const fs::path from = o.groom.empty() ? o.work : o.groom;
  const GroomInput groom = o.groom.empty()
                               ? read_groom(fur_outputs(o.work).strands(), fur_outputs(o.work).regions(), groom_roots_file(o.work), o.work)
                               : read_groom(SceneGroom{o.groom}.strands(), SceneGroom{o.groom}.regions(), SceneGroom{o.groom}.roots(), o.work);
  const knowledge::Knowledge knowledge = knowledge::read_knowledge(knowledge_outputs(o.work).knowledge());
  ExportScene scene;
  scene.bald_world = &bald;
  scene.body_colors = read_body_colors(o.work, bald.vertex_count());
  scene.frame = read_export_frame(export_outputs(o.work));
  scene.skeleton = &skeleton;
  scene.hair_diameter_mm = exporter::region_hair_diameter_mm(knowledge, {});
  const json e = o.groom.empty() ? json() : io::read_json_file(o.groom / "edit.json");  // checked to exist above
  if (e.contains("hair_diameter_mm")) {  // the edit's hair diameters (an edit made before them has none)
    for (int r = 0; r < body::kRegionCount; ++r) {
      const std::string name(body::kRegionNames[std::size_t(r)]);
      const io::JsonField v = io::JsonField(e, (o.groom / "edit.json").string()).at("hair_diameter_mm").at(name);
      if (!(v.number() > 0)) v.fail("expected a diameter above 0");
      scene.hair_diameter_mm[std::size_t(r)] = v.number();
    }
  }
  scene.skinning = exporter::skinning_transforms(skeleton, rotations);
  scene.title = "nf_gpu groom, posed";
  OutputFolder folder(o.out, "pose");
  const json exported = write_export(folder, groom, scene, export_options);
  json record{{"work", fs::absolute(o.work).string()}, {"groom", fs::absolute(from).string()}, {"joints", asked},
              {"rotation", "rotation vector in degrees, export frame (+x left, +y up, +z forward), about the joint"},
              {"seconds", t_all.seconds()}, {"export", exported}};
  write_file_atomic(folder.claim("pose.json"), record.dump(2) + "\n");
  folder.finish();
  return record;
}

}  // namespace nf::pipeline
