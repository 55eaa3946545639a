#pragma once
// The export folder that the export stage, `nf_gpu edit` and `nf_gpu pose` all write: the groom in
// four formats, the rigged body, the roots' places on the skin, and previews, in the export frame
// (export/export_frame.hpp: the animal upright, metres). Everything streams: the groom's points are
// read from its .hair file chunk by chunk for each format and never held whole.
#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "engine/body/regions.hpp"
#include "engine/core/json.hpp"
#include "engine/core/output_guard.hpp"
#include "engine/export/export_frame.hpp"
#include "engine/export/pose_groom.hpp"
#include "engine/io/scene.hpp"
#include "engine/io/skeleton.hpp"
#include "engine/io/strand_stream.hpp"

namespace nf::pipeline {

struct ExportOptions {
  // Groom files written (comma-separated): what the README's tools read by default; PLY and OBJ
  // (edge meshes, about as large again) on request.
  std::string formats = "usda,hair";
  double tip_width = 0.1;                     // a strand's width at the tip, as a share of its root width
  double width_scale = 1;                     // the root width as a multiple of a hair's diameter
  int turntable_frames = 12;                  // previews: frames around the animal (0: none)
  int compare_views = 3;                      // previews: held-out photos beside the groom's render (0: none)
  int preview_size = 512;                     // previews: longer side in pixels
  int preview_strands = 30000;                // previews: strands drawn (an even subset)
  // The formats as a list; UsageError naming an unknown one.
  std::vector<std::string> format_list() const;
};

// A groom to export: strands in world coordinates and scene units (any count, streamed), each
// strand's region and the M_bald face and barycentric coordinates of its root.
struct GroomInput {
  io::StrandStream strands;
  std::vector<std::int32_t> region;
  std::vector<std::uint32_t> root_face;
  std::vector<glm::vec3> root_barycentric;
  // The fur stage's colours (fur/strand_colors.hpp): `color_controls` per strand (strands x controls
  // x 3, linear RGB), or none.
  std::uint32_t color_controls = 0;
  std::vector<float> colors;
};

struct ExportScene {
  const geometry::Mesh* bald_world = nullptr;  // M_bald, world (normals, regions)
  const io::Skeleton* skeleton = nullptr;      // export frame, bound to bald_world's vertices
  exporter::ExportFrame frame;
  std::array<double, body::kRegionCount> hair_diameter_mm{};  // a hair's diameter at the root, per region
  // The body's colours from the photos (fur/body_colors.hpp): linear RGB per vertex of bald_world,
  // or empty (body.glb then has no COLOR_0 and the previews draw the body grey).
  std::vector<float> body_colors;
  // Previews: the scene's cameras and which are held out (photo beside the render).
  const io::Scene* scene = nullptr;
  std::vector<std::uint32_t> compare_cameras;
  // Posing (nf_gpu pose): the body's skinning transforms (export frame); empty: the bind pose.
  std::vector<glm::mat4> skinning;
  // index.html (export_page.hpp): its title and the figures the caller measured, in order.
  std::string title = "nf_gpu groom";
  std::vector<std::pair<std::string, std::string>> figures;
};

// Writes the files into `folder` and returns what export.json records (also written there):
// files, counts, the frame, seconds; and index.html, the page that shows them. InputError when an input is malformed (names the file).
json write_export(OutputFolder& folder, const GroomInput& groom, const ExportScene& scene, const ExportOptions& options);

// The groom as exported (export frame, metres; posed when scene.skinning is set), streamed: what
// the files hold. Also used by the tests to check the files against their source.
io::StrandStream exported_strands(const GroomInput& groom, const ExportScene& scene, const geometry::Mesh& body_export,
                                  const geometry::Mesh& posed_export);

}  // namespace nf::pipeline
