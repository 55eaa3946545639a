#pragma once
// The export stage (`export`): the fur stage's groom and M_bald as files artists load (fur.usda,
// fur.hair, fur.ply, fur.obj, the rigged body.glb), in metres with the animal upright, plus
// previews. Its files are ExportOutputs below; `nf_gpu reconstruct --help-stage export` lists its
// settings. `nf_gpu edit` and `nf_gpu pose` start from a finished export.
#include "engine/pipeline/export_files.hpp"
#include "engine/pipeline/stage.hpp"

namespace nf::pipeline {

struct ExportOutputs {
  std::filesystem::path dir;
  std::filesystem::path usda() const { return dir / "fur.usda"; }      // curves + body Mesh, one file for USD tools
  std::filesystem::path hair() const { return dir / "fur.hair"; }      // Cem Yuksel's format, with thickness
  std::filesystem::path ply() const { return dir / "fur.ply"; }        // vertex chains as edges, strands as an element
  std::filesystem::path obj() const { return dir / "fur.obj"; }        // `l` polylines
  std::filesystem::path body() const { return dir / "body.glb"; }      // M_bald, regions, skeleton, skin weights
  std::filesystem::path roots() const { return dir / "roots.npz"; }    // face, barycentric, region per strand
  std::filesystem::path record() const { return dir / "export.json"; } // frame, files, counts, seconds
};
inline ExportOutputs export_outputs(const std::filesystem::path& work) { return {work / "export"}; }

const SettingsSchema<ExportOptions>& export_settings();

// What an export records of its frame (export.json), for edit and pose. InputError naming the file.
exporter::ExportFrame read_export_frame(const ExportOutputs& outputs);

class ExportStage : public SettingsStage<ExportOptions> {
 public:
  ExportStage() : SettingsStage(export_settings()) {}
  std::vector<std::string> memory_settings() const override { return {"preview_size", "preview_strands"}; }
  std::vector<std::string> depends_on() const override { return {"fur"}; }
  std::vector<std::filesystem::path> inputs(const StageContext& context) const override;
  json parameters(const StageContext& context) const override;
  json run(StageContext& context, const std::filesystem::path& out, const std::filesystem::path& resume) override;
};

// The groom in scene units and the world frame that edit writes beside its export (what `nf_gpu
// metrics` and `render` read against the photos, and what pose --groom starts from).
struct SceneGroom {
  std::filesystem::path dir;
  std::filesystem::path strands() const { return dir / "scene_strands.hair"; }
  std::filesystem::path regions() const { return dir / "scene_regions.npz"; }
  std::filesystem::path roots() const { return dir / "scene_roots.npz"; }
};

// InputError unless WORK holds a finished export stage (what edit and pose start from).
void require_export(const std::filesystem::path& work);
// The skeleton the export stage bound to M_bald (body.glb), checked against `bald`'s vertex count.
io::Skeleton read_export_skeleton(const std::filesystem::path& work, const geometry::Mesh& bald);
// The export settings of `quality` without the photo comparisons (edit and pose have no photos),
// with `formats` when it is not empty (UsageError for an unknown format).
ExportOptions preview_options(const std::string& quality, const std::string& formats);

// The groom of a finished fur stage (or of an edit's folder): strands streamed from `strands`
// (.hair), regions from `regions` (.npz `region`), roots from `roots` (roots.npz), and with the fur
// stage's colours in `work` (fur/colors.npz) each strand takes the colours of the fur stage's strand
// whose root is nearest its own (itself, for the fur stage's groom; an edit's strands grow on the
// same body). InputError when the counts disagree, naming the files.
GroomInput read_groom(const std::filesystem::path& strands, const std::filesystem::path& regions, const std::filesystem::path& roots,
                      const std::filesystem::path& work);
// The fur stage's body colours in `work` (fur/body_colors.npz) for a body of `vertices` vertices:
// linear RGB per vertex, or empty when there are none or they belong to another body (a fur stage
// on the true body, `fur.truth=all`; said in a warning). InputError when the file is malformed.
std::vector<float> read_body_colors(const std::filesystem::path& work, std::uint64_t vertices);

}  // namespace nf::pipeline
