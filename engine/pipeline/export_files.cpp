#include "engine/pipeline/export_files.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/interrupt.hpp"
#include "engine/core/log.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/fur/strand_colors.hpp"
#include "engine/pipeline/export_page.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/io/image.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/npz.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/io/view_names.hpp"
#include "engine/synth/camera_rig.hpp"
#include "engine/synth/preview.hpp"
#include "engine/synth/strand_renderer.hpp"

namespace nf::pipeline {
namespace fs = std::filesystem;
namespace {

// A camera of the scene (world) seen in the export frame, its image scaled to `max_side`.
io::Camera camera_in_export(const io::Camera& cam, const exporter::ExportFrame& frame, int max_side) {
  io::Camera c = io::reduced_to(cam, std::uint32_t(max_side));
  glm::dmat4 m = frame.world_to_export * cam.camera_to_world;
  for (int a = 0; a < 3; ++a) m[a] = glm::dvec4(glm::normalize(glm::dvec3(m[a])), 0.0);  // rigid again
  c.camera_to_world = m;
  return c;
}

io::Image side_by_side(const std::vector<io::Image>& images) {
  io::Image out;
  out.channels = 3;
  for (const io::Image& i : images) out.width += i.width, out.height = std::max(out.height, i.height);
  out.pixels.assign(std::size_t(out.width) * out.height * 3, 0.f);
  std::uint32_t x0 = 0;
  for (const io::Image& i : images) {
    for (std::uint32_t y = 0; y < i.height; ++y)
      for (std::uint32_t x = 0; x < i.width; ++x)
        for (std::uint32_t c = 0; c < 3; ++c) out.pixels[(std::size_t(y) * out.width + x0 + x) * 3 + c] = i.at(x, y, std::min(c, i.channels - 1));
    x0 += i.width;
  }
  return out;
}

io::Image contact_sheet(const std::vector<io::Image>& frames, std::uint32_t columns) {
  if (frames.empty()) return {};
  const std::uint32_t w = frames[0].width, h = frames[0].height, rows = (std::uint32_t(frames.size()) + columns - 1) / columns;
  io::Image out{w * columns, h * rows, 3, std::vector<float>(std::size_t(w) * columns * h * rows * 3, 0.f)};
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const std::uint32_t ox = std::uint32_t(f % columns) * w, oy = std::uint32_t(f / columns) * h;
    for (std::uint32_t y = 0; y < h && y < frames[f].height; ++y)
      for (std::uint32_t x = 0; x < w && x < frames[f].width; ++x)
        for (std::uint32_t c = 0; c < 3; ++c) out.pixels[(std::size_t(oy + y) * out.width + ox + x) * 3 + c] = frames[f].at(x, y, c);
  }
  return out;
}

}  // namespace

std::vector<std::string> ExportOptions::format_list() const {
  std::vector<std::string> out;
  std::stringstream words(formats);
  std::string f;
  while (std::getline(words, f, ',')) {
    if (f.empty()) continue;
    if (f != "usda" && f != "hair" && f != "ply" && f != "obj")
      throw UsageError("export.formats: '" + f + "' is not a groom format (usda, hair, ply, obj)");
    if (std::find(out.begin(), out.end(), f) == out.end()) out.push_back(f);
  }
  return out;
}

io::StrandStream exported_strands(const GroomInput& g, const ExportScene& sc, const geometry::Mesh& body_export,
                                  const geometry::Mesh& posed_export) {
  io::StrandStream s = g.strands;
  const bool posed = !sc.skinning.empty();
  s.each_chunk = [&g, &sc, &body_export, &posed_export, posed, source = g.strands](const io::PointSink& sink) {
    io::StrandCursor at(source);
    std::uint64_t motion_of = ~0ull;
    exporter::RootMotion motion;
    std::vector<float> out;
    source.each_chunk([&](std::span<const float> xyz) {
      stop_if_interrupted("export");  // a stop mid-file removes the partial file
      out.resize(xyz.size());
      for (std::size_t p = 0; p < xyz.size() / 3; ++p, at.next()) {
        glm::vec3 q = sc.frame.point({xyz[3 * p], xyz[3 * p + 1], xyz[3 * p + 2]});
        if (posed) {
          if (motion_of != at.strand())
            motion = exporter::root_motion(body_export, posed_export, g.root_face[at.strand()], g.root_barycentric[at.strand()]), motion_of = at.strand();
          q = motion.apply(q);
        }
        out[3 * p] = q.x, out[3 * p + 1] = q.y, out[3 * p + 2] = q.z;
      }
      sink(std::span<const float>(out));
    });
  };
  return s;
}

json write_export(OutputFolder& folder, const GroomInput& g, const ExportScene& sc, const ExportOptions& o) {
  const Stopwatch t_all;
  json seconds = json::object(), files = json::array();
  Stopwatch t;
  const std::uint64_t n = g.strands.strands;
  if (g.region.size() != n || g.root_face.size() != n || g.root_barycentric.size() != n ||
      (g.color_controls && g.colors.size() != n * g.color_controls * 3))
    throw InternalError("export: per-strand arrays do not match the strand count");
  NF_CHECK(sc.bald_world && sc.skeleton, "export: the body and its skeleton are needed");
  NF_CHECK(sc.body_colors.empty() || sc.body_colors.size() == 3 * sc.bald_world->vertex_count(), "export: body colours of another mesh");
  const geometry::Mesh body_export = exporter::to_export(*sc.bald_world, sc.frame);
  const bool posed = !sc.skinning.empty();
  const geometry::Mesh posed_export = posed ? exporter::skin_mesh(body_export, *sc.skeleton, sc.skinning) : body_export;
  for (std::size_t i = 0; i < n; ++i)
    if (g.root_face[i] >= body_export.triangle_count()) throw InputError("export: strand " + std::to_string(i) + "'s root face is not a face of M_bald");

  // Widths: the region's hair diameter at the root (mm -> m) times width_scale, tapering linearly to
  // tip_width of it.
  std::array<float, body::kRegionCount> root_width{};
  for (int r = 0; r < body::kRegionCount; ++r) root_width[std::size_t(r)] = float(sc.hair_diameter_mm[std::size_t(r)] / 1000.0 * o.width_scale);
  io::StrandStream s = exported_strands(g, sc, body_export, posed_export);
  s.frame = io::FileFrame::exported;
  const double taper = 1.0 - o.tip_width;
  s.width = [&g, &root_width, &s, taper](std::uint64_t i, std::uint32_t k) {
    const std::int32_t r = g.region[i];
    const float w = r >= 0 && r < body::kRegionCount ? root_width[std::size_t(r)] : 0.f;
    const std::uint32_t count = s.points_in(i);
    return float(double(w) * (1.0 - taper * (count > 1 ? double(k) / double(count - 1) : 0.0)));
  };
  s.region = [&g](std::uint64_t i) { return g.region[i]; };
  if (g.color_controls)
    s.color = [&g, &s](std::uint64_t i, std::uint32_t k) {
      const std::uint32_t count = s.points_in(i);
      return fur::control_color(&g.colors[std::size_t(i) * g.color_controls * 3], g.color_controls, count > 1 ? float(k) / float(count - 1) : 1.f);
    };

  for (const std::string& f : o.format_list()) {
    t.restart();
    const fs::path path = folder.claim("fur." + f);
    if (f == "usda") {
      io::UsdaScene usd;
      usd.meters_per_unit = 1.0;
      usd.body = &posed_export;
      usd.body_colors = sc.body_colors;
      usd.root_face = [&g](std::uint64_t i) { return g.root_face[i]; };
      usd.root_barycentric = [&g](std::uint64_t i) { return g.root_barycentric[i]; };
      io::write_strands_usda(path, s, usd);
    } else if (f == "hair") {
      io::write_hair(path, s);
    } else if (f == "ply") {
      io::write_strands_ply(path, s);
    } else {
      io::write_strands_obj(path, s);
    }
    seconds[f] = t.seconds();
    files.push_back({{"file", path.filename().string()}, {"bytes", fs::file_size(path)}});
    log::info("export: ", path.filename().string(), " (", double(fs::file_size(path)) / 1e6, " MB) in ", seconds[f].get<double>(), " s");
  }

  // The rigged body; a posed export binds the posed body to the posed joints.
  t.restart();
  io::Skeleton skeleton = *sc.skeleton;
  if (posed)
    for (std::size_t j = 0; j < skeleton.joint_count(); ++j)
      skeleton.joint_positions[j] = glm::vec3(sc.skinning[j] * glm::vec4(skeleton.joint_positions[j], 1.f));
  const fs::path glb = folder.claim("body.glb");
  {
    // glTF's COLOR_0 lies in [0, 1]; the photos' colours may exceed 1 after a view's exposure gain.
    std::vector<float> clamped(sc.body_colors);
    for (float& c : clamped) c = std::clamp(c, 0.f, 1.f);
    io::write_mesh_glb(glb, posed_export, &skeleton, io::FileFrame::exported, clamped);
  }
  files.push_back({{"file", "body.glb"}, {"bytes", fs::file_size(glb)}});
  {
    io::NpyWrite face{"face", {n}, "<u4", {}}, bary{"barycentric", {n, 3}, "<f4", {}}, region{"region", {n}, "<i4", {}};
    face.values.reserve(n), bary.values.reserve(3 * n), region.values.reserve(n);
    for (std::uint64_t i = 0; i < n; ++i) {
      face.values.push_back(g.root_face[i]), region.values.push_back(g.region[i]);
      bary.values.insert(bary.values.end(), {g.root_barycentric[i].x, g.root_barycentric[i].y, g.root_barycentric[i].z});
    }
    const fs::path roots = folder.claim("roots.npz");
    io::write_npz(roots, {face, bary, region});
    files.push_back({{"file", "roots.npz"}, {"bytes", fs::file_size(roots)}});
  }
  seconds["body"] = t.seconds();

  // Previews: an even subset of the strands over the body.
  t.restart();
  json previews = json::object();
  if ((o.turntable_frames > 0 || (o.compare_views > 0 && !posed && sc.scene)) && o.preview_strands > 0 && n > 0) {
    const std::uint64_t every = std::max<std::uint64_t>(1, n / std::uint64_t(o.preview_strands));
    io::StrandSet subset;
    subset.offsets.push_back(0);
    {
      io::StrandCursor at(s);
      s.each_chunk([&](std::span<const float> xyz) {
        for (std::size_t p = 0; p < xyz.size() / 3; ++p, at.next())
          if (at.strand() % every == 0) {
            subset.points.insert(subset.points.end(), xyz.begin() + std::ptrdiff_t(3 * p), xyz.begin() + std::ptrdiff_t(3 * p + 3));
            if (at.k() + 1 == s.points_in(at.strand())) subset.offsets.push_back(std::uint32_t(subset.points.size() / 3));
          }
      });
    }
    synth::StrandLook look;
    // The strands' own colours (their tip's: the renderer shades the root side darker), else their
    // regions' palette.
    for (std::uint64_t i = 0; i < n; i += every)
      look.root_colors.push_back(g.color_controls ? fur::control_color(&g.colors[std::size_t(i) * g.color_controls * 3], g.color_controls, 1.f)
                                                  : synth::linear(synth::palette_color(g.region[i])));
    const geometry::Bounds box = geometry::mesh_bounds(posed_export);
    const glm::vec3 centre = 0.5f * (box.lo + box.hi);
    const float radius = 0.5f * glm::length(box.hi - box.lo);
    synth::RigOptions rig;
    rig.width = rig.height = std::uint32_t(o.preview_size);
    rig.views = std::uint32_t(std::max(2, o.turntable_frames + o.turntable_frames % 2));
    rig.low_elevation_deg = rig.high_elevation_deg = 15.f;
    const std::vector<io::Camera> ring = synth::camera_rings(centre, radius, {0, 1, 0}, rig);
    // About a pixel wide at the animal in the turntable.
    const double distance = glm::length(glm::dvec3(ring[0].camera_to_world[3]) - glm::dvec3(centre));
    look.radius = float(0.75 * distance / ring[0].fy);
    synth::BodyLook body_look;
    body_look.vertex_colors.assign(posed_export.vertex_count(), synth::linear(glm::vec3(0.62f)));
    for (std::size_t v = 0; v < sc.body_colors.size() / 3; ++v)
      body_look.vertex_colors[v] = {sc.body_colors[3 * v], sc.body_colors[3 * v + 1], sc.body_colors[3 * v + 2]};
    synth::RenderOptions render_options;
    render_options.samples_per_axis = 2;
    const synth::StrandRenderer renderer(posed_export, body_look, subset, look, render_options);
    if (o.turntable_frames > 0) {
      std::vector<io::Image> frames;
      json frame_files = json::array();
      const std::uint32_t half = rig.views / 2;
      for (std::uint32_t k = 0; k < std::uint32_t(o.turntable_frames); ++k) {
        const io::Camera& cam = ring[k % 2 ? half + k / 2 : k / 2];
        frames.push_back(renderer.render(cam).rgb);
        char name[32];
        std::snprintf(name, sizeof name, "turntable_%03u.png", k);
        io::write_png(folder.claim(name), frames.back());
        frame_files.push_back(name);
      }
      for (io::Image& f : frames) f = io::downscale_to(f, std::uint32_t(o.preview_size / 2));
      io::write_png(folder.claim("turntable.png"), contact_sheet(frames, 4));
      previews["turntable"] = {{"frames", frames.size()}, {"sheet", "turntable.png"}, {"files", frame_files}};
    }
    if (o.compare_views > 0 && !posed && sc.scene) {
      json compared = json::array();
      const std::vector<std::string> names = io::view_file_names(*sc.scene, sc.compare_cameras);
      for (std::size_t i = 0; i < sc.compare_cameras.size() && int(i) < o.compare_views; ++i) {
        const io::Camera& cam = sc.scene->cameras[sc.compare_cameras[i]];
        if (cam.image.empty()) continue;
        const io::Camera view = camera_in_export(cam, sc.frame, o.preview_size);
        const io::Image photo = io::downscale_to(io::read_image(cam.image), std::max(view.width, view.height));
        const fs::path file = folder.claim("compare_" + names[i] + ".png");
        io::write_png(file, side_by_side({photo, renderer.render(view).rgb}));
        compared.push_back(file.filename().string());
      }
      previews["compare"] = compared;
    }
  }
  seconds["previews"] = t.seconds();

  json record{{"strands", n},
              {"points", g.strands.points},
              {"files", files},
              {"frame", sc.frame.to_json()},
              {"widths", {{"root", "the region's hair_diameter_mm x width_scale"}, {"width_scale", o.width_scale}, {"tip_share", o.tip_width}, {"unit", "metre"}}},
              {"joints", sc.skeleton->joint_count()},
              {"posed", posed},
              {"previews", previews},
              {"seconds", seconds}};
  ExportPage page;
  page.title = sc.title;
  page.figures = sc.figures;
  page.figures.insert(page.figures.begin(), {"strands", std::to_string(n) + (g.color_controls ? ", coloured from the photos" : "")});
  page.files = files;
  if (previews.contains("turntable"))
    for (const json& f : previews["turntable"]["files"]) page.turntable.push_back(f.get<std::string>());
  if (previews.contains("compare"))
    for (const json& f : previews["compare"]) page.compare.push_back(f.get<std::string>());
  write_file_atomic(folder.claim("index.html"), export_page_html(page));
  record["page"] = "index.html";
  record["seconds_total"] = t_all.seconds();
  write_file_atomic(folder.claim("export.json"), record.dump(2) + "\n");
  return record;
}

}  // namespace nf::pipeline
