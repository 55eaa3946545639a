#include "engine/synth/preview.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "engine/core/output_guard.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/parallel.hpp"
#include "engine/core/progress.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/io/image.hpp"
#include "engine/core/color.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/scene.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/io/view_names.hpp"
#include "engine/synth/strand_renderer.hpp"

namespace nf::synth {
namespace fs = std::filesystem;

glm::vec3 linear(glm::vec3 srgb) { return color::srgb_to_linear(srgb); }

glm::vec3 palette_color(std::int64_t region) {
  const auto& p = region_palette();
  if (region < 0 || region >= std::int64_t(p.size())) return p[std::size_t(body::Region::body)];
  return p[std::size_t(region)];
}

namespace {

// 0.5 x the median over cameras of depth(animal centre) / focal length, in scene units.
float default_radius(const io::Scene& scene, const geometry::Mesh& mesh) {
  glm::dvec3 lo(1e300), hi(-1e300);
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i)
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], double(mesh.positions[3 * i + c]));
      hi[c] = std::max(hi[c], double(mesh.positions[3 * i + c]));
    }
  const glm::dvec3 centre = mesh.vertex_count() ? 0.5 * (lo + hi) : glm::dvec3(0);
  std::vector<double> footprints;
  for (const io::Camera& cam : scene.cameras) {
    const double depth = cam.project(centre).z;
    if (depth > 0 && std::isfinite(depth)) footprints.push_back(depth / (0.5 * (cam.fx + cam.fy)));
  }
  if (footprints.empty())
    throw InputError("scene " + scene.root.string() +
                     ": no camera sees the body mesh's centre in front of it; cannot size the strands");
  std::nth_element(footprints.begin(), footprints.begin() + footprints.size() / 2, footprints.end());
  return float(0.5 * footprints[footprints.size() / 2]);
}

}  // namespace

const std::array<glm::vec3, body::kRegionCount>& region_palette() {
  // sRGB, moderately bright so that the renderer's lighting rarely clips them (hues stay readable).
  static const std::array<glm::vec3, body::kRegionCount> palette = {{
      {0.90f, 0.33f, 0.28f},  // leg_front: red
      {0.93f, 0.58f, 0.18f},  // leg_rear: orange
      {0.55f, 0.36f, 0.22f},  // paw_pads: brown
      {0.86f, 0.80f, 0.22f},  // paws: yellow
      {0.55f, 0.82f, 0.24f},  // front_paws: lime
      {0.20f, 0.66f, 0.33f},  // belly: green
      {0.18f, 0.74f, 0.70f},  // neck: teal
      {0.24f, 0.50f, 0.92f},  // face: blue
      {0.52f, 0.34f, 0.86f},  // ears: violet
      {0.88f, 0.38f, 0.76f},  // inner_earcanal: magenta
      {0.96f, 0.68f, 0.70f},  // under_tail: pink
      {0.16f, 0.20f, 0.48f},  // eyes: navy
      {0.68f, 0.16f, 0.42f},  // tail: plum
      {0.52f, 0.54f, 0.12f},  // nosetip: olive
      {0.82f, 0.60f, 0.40f},  // body: tan
      {0.45f, 0.72f, 0.96f},  // mane: sky blue
  }};
  return palette;
}

PreviewResult render_previews(const PreviewOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  if (o.samples_per_axis < 1 || o.samples_per_axis > 16)
    throw UsageError("--spp-axis must lie in [1, 16], got " + std::to_string(o.samples_per_axis));
  if (!(o.width_scale > 0) || !std::isfinite(o.width_scale))
    throw UsageError("--width-scale must be a positive number, got " + std::to_string(o.width_scale));
  if (o.out.empty()) throw UsageError("--out: an output folder is needed");

  const io::Scene scene = io::read_scene(o.scene);
  scene.validate(o.scene.string());
  refuse_output_inside(o.out, scene.root, "--out", "scene");
  require_folder_or_absent(o.out, "--out");
  const std::vector<std::uint32_t> views = io::parse_view_list(o.views, scene.cameras.size());
  // The scene's cameras draw them: an export-frame file comes back into the scene's frame.
  const io::CommonFrame frame = io::common_frame({o.mesh, o.strands}, true);
  geometry::Mesh mesh = io::read_mesh(o.mesh);
  mesh.validate(o.mesh.string());
  if (mesh.triangle_count() == 0) throw InputError(o.mesh.string() + ": the body mesh has no triangles");
  io::transform_points(mesh.positions, frame.to_common[0]);
  if (frame.moved[0]) mesh.normals.clear();  // recomputed below
  io::StrandSet strands = io::read_strands(o.strands);
  strands.validate(o.strands.string());
  io::transform_points(strands.points, frame.to_common[1]);
  if (mesh.normals.empty()) geometry::compute_vertex_normals(mesh);

  PreviewResult result;
  // Colours per strand.
  StrandLook look;
  const std::uint32_t n = strands.strand_count();
  look.root_colors.assign(n, linear(palette_color(std::int32_t(body::Region::body))));
  if (!strands.regions.empty()) {
    result.coloring = "strand regions";
    for (std::uint32_t s = 0; s < n; ++s) look.root_colors[s] = linear(palette_color(strands.regions[s]));
  } else if (!mesh.regions.empty() && mesh.vertex_count() > 0) {
    result.coloring = "nearest body vertex region";
    const geometry::PointIndex index(mesh.positions);
    parallel_for(n, [&](std::size_t s0, std::size_t s1) {
      for (std::size_t s = s0; s < s1; ++s) {
        if (strands.points_in(std::uint32_t(s)) == 0) continue;
        const float* root = &strands.points[3 * std::size_t(strands.offsets[s])];
        look.root_colors[s] = linear(palette_color(mesh.regions[index.nearest(root).first]));
      }
    });
  } else {
    result.coloring = "single colour";
  }
  result.strand_radius = float(double(default_radius(scene, mesh)) * o.width_scale);
  look.radius = result.strand_radius;
  BodyLook body_look;
  body_look.vertex_colors.assign(mesh.vertex_count(), linear(glm::vec3(0.62f)));
  RenderOptions render_options;
  render_options.samples_per_axis = o.samples_per_axis;
  const StrandRenderer renderer(mesh, body_look, strands, look, render_options);

  // File names: file-safe camera names, made unique with the camera index.
  const std::vector<std::string> names = io::view_file_names(scene, views);
  OutputFolder folder(o.out, "render");
  Progress progress("render", views.size());
  for (std::size_t i = 0; i < views.size(); ++i) {
    const io::Camera& cam = scene.cameras[views[i]];
    const Rendered r = renderer.render(cam);
    const fs::path file = folder.claim(names[i] + ".png");
    io::write_png(file, r.rgb);
    result.files.push_back(file);
    progress.update(i + 1);
  }
  progress.finish();
  folder.finish();  // one result per folder: an earlier run's other views go
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  log::info("render: ", views.size(), " views, ", n, " strands coloured by ", result.coloring, ", radius ",
            result.strand_radius, " -> ", o.out.string());
  return result;
}

std::vector<io::Image> render_region_images(const geometry::Mesh& mesh, const io::Scene& scene,
                                            const std::vector<std::uint32_t>& views) {
  geometry::Mesh body = mesh;
  if (body.normals.empty()) geometry::compute_vertex_normals(body);
  BodyLook look;
  look.vertex_colors.assign(body.vertex_count(), linear(palette_color(std::int32_t(body::Region::body))));
  for (std::size_t i = 0; i < body.regions.size(); ++i) look.vertex_colors[i] = linear(palette_color(body.regions[i]));
  RenderOptions options;
  options.samples_per_axis = 2;
  const StrandRenderer renderer(body, look, io::StrandSet{}, StrandLook{}, options);
  std::vector<io::Image> images;
  for (std::uint32_t v : views) images.push_back(renderer.render(scene.cameras[v]).rgb);
  return images;
}

std::vector<fs::path> render_region_previews(const geometry::Mesh& mesh, const io::Scene& scene,
                                            const std::vector<std::uint32_t>& views, const fs::path& out) {
  const std::vector<io::Image> images = render_region_images(mesh, scene, views);
  const std::vector<std::string> names = io::view_file_names(scene, views);
  OutputFolder folder(out, "previews");
  std::vector<fs::path> files;
  for (std::size_t i = 0; i < views.size(); ++i) {
    files.push_back(folder.claim(names[i] + ".png"));
    io::write_png(files.back(), images[i]);
  }
  return files;
}

}  // namespace nf::synth
