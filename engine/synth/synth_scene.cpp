#include "engine/synth/synth_scene.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/body/quadruped.hpp"
#include "engine/core/output_guard.hpp"
#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/core/progress.hpp"
#include "engine/core/random.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/io/image.hpp"
#include "engine/io/jpeg_exif.hpp"
#include "engine/io/json_fields.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/scene.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/knowledge/knowledge.hpp"
#include "engine/synth/camera_rig.hpp"
#include "engine/synth/effective_thickness.hpp"
#include "engine/synth/fur_envelope.hpp"
#include "engine/synth/fur_growth.hpp"
#include "engine/synth/photo_effects.hpp"
#include "engine/synth/strand_renderer.hpp"
#include "engine/synth/world_frame.hpp"

namespace nf::synth {

namespace fs = std::filesystem;

namespace {

constexpr float kCmPerUnit = 100.0f;  // synthetic scenes are in metres

class Stopwatch {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// The output folder must be new, or an earlier synth output when overwriting is allowed.
void check_destination(const fs::path& out, bool overwrite) {
  if (!fs::exists(out)) return;
  require_folder_or_absent(out, "--out");
  if (fs::is_empty(out)) return;
  const bool ours = fs::exists(out / "gt" / "scene.json") && fs::exists(out / "transforms.json");
  if (!ours) throw UsageError(out.string() + " exists and is not an nf_gpu synth scene; nothing was written (choose another --out)");
  if (!overwrite) throw UsageError(out.string() + " already holds a synth scene; pass --overwrite to replace it");
}

}  // namespace

json synthesize_scene(const fs::path& requested_out, const SynthOptions& o) {
  if (o.views == 0 || o.resolution < 8 || o.resolution > 8192) throw UsageError("synth: --views must be >= 1 and --res in [8, 8192]");
  if (o.strands == 0) throw UsageError("synth: --strands must be >= 1");
  if (!(o.hair_width > 0 && o.hair_width <= 100)) throw UsageError("synth: --hair-width must lie in (0, 100], got " + std::to_string(o.hair_width));
  if (!(o.photo_noise >= 0 && o.photo_noise <= 255)) throw UsageError("synth: --noise must lie in [0, 255], got " + std::to_string(o.photo_noise));
  if (!(o.proportion_spread >= 0 && o.proportion_spread <= 0.3f))
    throw UsageError("synth: --proportion-spread must lie in [0, 0.3], got " + std::to_string(o.proportion_spread));
  if (!(o.fur_length_spread >= 0 && o.fur_length_spread <= 0.9f))
    throw UsageError("synth: --fur-length-spread must lie in [0, 0.9], got " + std::to_string(o.fur_length_spread));
  hair_shading_from(o.shading);  // an unknown shading fails before any work
  if (o.photo_format != "png" && o.photo_format != "jpeg") throw UsageError("synth: --photo-format must be png or jpeg, got " + o.photo_format);
  if (o.camera_path != "rings" && o.camera_path != "handheld") throw UsageError("synth: --path must be rings or handheld, got " + o.camera_path);
  if (o.blurred_views > o.views) throw UsageError("synth: --blurred-views " + std::to_string(o.blurred_views) + " is more than the " + std::to_string(o.views) + " views");
  const bool textured_backdrop = backdrop_is_textured(o.backdrop);
  const WorldFrame frame = world_frame(o.frame);
  // "scenes/cat/" and "scenes/./cat" name the same folder; the temp folder sits beside it.
  fs::path out_dir = fs::absolute(requested_out).lexically_normal();
  if (!out_dir.has_filename()) out_dir = out_dir.parent_path();
  if (out_dir == out_dir.root_path()) throw UsageError("synth: --out must name a folder, not " + out_dir.string());
  check_destination(out_dir, o.overwrite);
  const fs::path out = out_dir.parent_path() / (out_dir.filename().string() + ".partial");
  fs::remove_all(out);
  fs::create_directories(out / "images");
  fs::create_directories(out / "masks");
  fs::create_directories(out / "gt");
  Stopwatch clock;
  json timings;

  // Body: the family's proportions for the animal, varied by the seed, posed mildly.
  const body::QuadrupedProportions proportions = body::vary_proportions(body::animal_proportions(o.animal), o.seed, o.proportion_spread);
  const body::BodyModel model = body::build_quadruped(proportions, {o.body_voxel});
  body::BodyParams params = body::random_pose(model, o.seed);
  std::mt19937 rng(o.seed + 101);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  // A yaw and an offset so the world frame differs from the animal frame.
  params.animal_to_world = glm::translate(glm::mat4(1.0f), 0.1f * proportions.torso_length * glm::vec3(u(rng), 0, u(rng))) *
                           glm::rotate(glm::mat4(1.0f), 3.14159265f * u(rng), glm::vec3(0, 1, 0));
  const geometry::Mesh bald = body::pose_body(model, params);
  const body::EyeCentres eyes = body::eye_centres(model, params);
  timings["body_s"] = clock.lap();
  log::write(log::Level::Info, "synth: " + o.animal + " body, " + std::to_string(bald.vertex_count()) + " vertices");

  // Fur from the animal's knowledge preset, each region's length scaled by --fur-length-spread; the
  // ground-truth knowledge carries the true eye distance. (The thickness scaled with it stays only
  // where the grown fur gives none, below.)
  knowledge::Knowledge know = knowledge::preset(o.animal);
  know.eye_distance_cm = eyes.distance() * kCmPerUnit;
  if (o.fur_length_spread > 0) {
    std::mt19937 length_rng(o.seed * 7919u + 3u);
    std::uniform_real_distribution<float> factor(1.0f - o.fur_length_spread, 1.0f + o.fur_length_spread);
    for (std::optional<knowledge::RegionKnowledge>& region : know.regions)
      if (region) {
        const float f = factor(length_rng);
        region->length_cm *= f;
        region->thickness_cm *= f;
      }
  }
  const FurStyle style = fur_style(o.animal);
  GrowOptions grow;
  grow.strand_count = o.strands, grow.points_per_strand = o.points_per_strand, grow.seed = o.seed;
  grow.cm_per_unit = kCmPerUnit, grow.animal_to_world = params.animal_to_world;
  grow.animal = o.animal, grow.torso_length = proportions.torso_length;
  Fur fur = grow_fur(bald, know, style, grow);
  timings["fur_s"] = clock.lap();

  const Envelope envelope = fur_envelope(bald, fur.strands);
  timings["envelope_s"] = clock.lap();
  // The ground-truth knowledge states the thickness the grown fur has, not the preset's guess.
  const std::array<float, body::kRegionCount> thickness = effective_thickness(bald, envelope.mesh);
  for (std::size_t r = 0; r < thickness.size(); ++r) {
    std::optional<knowledge::RegionKnowledge>& k = know.regions[r];
    if (k && k->length_cm > 0 && thickness[r] >= 0) k->thickness_cm = std::min(k->length_cm, float(thickness[r] * kCmPerUnit));
  }
  timings["thickness_s"] = clock.lap();

  // Cameras on two rings around the envelope's bounding sphere.
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (std::size_t i = 0; i < envelope.mesh.vertex_count(); ++i) {
    const glm::vec3 p(envelope.mesh.positions[3 * i], envelope.mesh.positions[3 * i + 1], envelope.mesh.positions[3 * i + 2]);
    lo = glm::min(lo, p), hi = glm::max(hi, p);
  }
  const glm::vec3 centre = 0.5f * (lo + hi);
  float radius = 0;
  for (std::size_t i = 0; i < envelope.mesh.vertex_count(); ++i)
    radius = std::max(radius, glm::distance(centre, glm::vec3(envelope.mesh.positions[3 * i], envelope.mesh.positions[3 * i + 1],
                                                              envelope.mesh.positions[3 * i + 2])));
  RigOptions rig;
  rig.views = o.views, rig.width = rig.height = o.resolution;
  rig.handheld = o.camera_path == "handheld", rig.seed = o.seed;
  const glm::vec3 up = glm::normalize(glm::vec3(params.animal_to_world * glm::vec4(0, 1, 0, 0)));
  io::Scene scene;
  scene.root = out;
  scene.cm_per_unit = kCmPerUnit;
  scene.cameras = camera_rings(centre, radius, up, rig);

  // Render.
  BodyLook body_look;
  for (std::int32_t r : bald.regions) body_look.vertex_colors.push_back(skin_color(o.animal, static_cast<body::Region>(r)));
  StrandLook look;
  look.root_colors = fur.root_colors;
  look.radius = style.strand_radius_fraction * proportions.torso_length * o.hair_width;
  RenderOptions render_options;
  render_options.samples_per_axis = o.samples_per_axis;
  render_options.shading = hair_shading_from(o.shading);
  render_options.true_orientation = o.true_orientation;
  if (textured_backdrop) {
    // The floor under the lowest paw, the wall well behind the farthest camera, blotches a tenth of
    // the animal's radius.
    Backdrop& room = render_options.backdrop;
    room.textured = true;
    room.centre = centre;
    room.floor_y = 1e30f;
    for (std::size_t i = 0; i < bald.vertex_count(); ++i) room.floor_y = std::min(room.floor_y, bald.positions[3 * i + 1]);
    float farthest = 0;
    for (const io::Camera& cam : scene.cameras)
      farthest = std::max(farthest, glm::length(glm::vec2(float(cam.camera_to_world[3].x) - centre.x, float(cam.camera_to_world[3].z) - centre.z)));
    room.wall_radius = 2.5f * farthest;
    room.feature_size = 0.1f * radius;
  }
  if (o.true_orientation) fs::create_directories(out / "gt" / "orientation");
  const StrandRenderer renderer(bald, body_look, fur.strands, look, render_options);
  timings["render_setup_s"] = clock.lap();
  Progress progress("synth render", scene.cameras.size());
  double coverage_sum = 0;
  for (std::size_t i = 0; i < scene.cameras.size(); ++i) {
    io::Camera& cam = scene.cameras[i];
    Rendered r = renderer.render(cam);
    if (o.photo_noise > 0) {
      // Sensor noise on the stored values, as a camera adds it before encoding.
      std::mt19937_64 noise_rng(splitmix64(std::uint64_t(o.seed) * 1000003u + i));
      std::normal_distribution<float> noise(0.f, o.photo_noise / 255.f);
      for (float& v : r.rgb.pixels) v = std::clamp(v + noise(noise_rng), 0.f, 1.f);
    }
    // The blurred views spread evenly: the middle one of each of `blurred_views` equal runs.
    if (const std::size_t run = o.blurred_views ? scene.cameras.size() / o.blurred_views : 0; run > 0 && i % run == run / 2 && i / run < o.blurred_views)
      r.rgb = motion_blur(r.rgb, std::max(3u, o.resolution * 3 / 200));
    const bool jpeg = o.photo_format == "jpeg";
    cam.image = out / "images" / (cam.name + (jpeg ? ".jpg" : ".png"));
    cam.mask = out / "masks" / (cam.name + ".png");
    io::Image mask{r.coverage.width, r.coverage.height, 1, std::vector<float>(r.coverage.pixels.size())};
    for (std::size_t p = 0; p < mask.pixels.size(); ++p) mask.pixels[p] = r.coverage.pixels[p] >= 0.5f ? 1.0f : 0.0f;
    for (float c : mask.pixels) coverage_sum += c;
    if (jpeg) {
      const double focal_mm = cam.fx * 36.0 / double(std::max(cam.width, cam.height));
      write_file_atomic(cam.image, io::with_exif(io::encode_jpeg(r.rgb, 92), {"nf_gpu", "synth camera", focal_mm, focal_mm}));
    } else {
      io::write_png(cam.image, r.rgb);
    }
    io::write_png(cam.mask, mask);
    if (o.true_orientation) io::write_exr(out / "gt" / "orientation" / (cam.name + ".exr"), r.orientation);
    progress.update(i + 1);
  }
  progress.finish();
  timings["render_s"] = clock.lap();

  // Ground truth and cameras, in the asked world frame (the photos do not change with it).
  const auto to_world = [&](geometry::Mesh mesh) {
    geometry::transform_mesh(mesh, frame.matrix());
    return mesh;
  };
  for (io::Camera& cam : scene.cameras) transform_camera(frame, cam);
  scene.cm_per_unit = kCmPerUnit / frame.scale;
  transform_strands(frame, fur.strands);
  // The true strands carry their colour per point (linear RGB), what the groom's colours are scored against.
  fur.strands.colors.resize(3 * fur.strands.point_count());
  for (std::uint32_t s = 0; s < fur.strands.strand_count(); ++s)
    for (std::uint32_t k = 0, n = fur.strands.points_in(s); k < n; ++k) {
      const glm::vec3 c = strand_albedo(fur.root_colors[s], n > 1 ? float(k) / float(n - 1) : 1.f);
      const std::size_t p = 3 * (std::size_t(fur.strands.offsets[s]) + k);
      fur.strands.colors[p] = c.r, fur.strands.colors[p + 1] = c.g, fur.strands.colors[p + 2] = c.b;
    }
  const geometry::Mesh bald_world = to_world(bald);
  io::write_transforms_json(out / "transforms.json", scene);
  io::write_hair(out / "gt" / "strands.hair", fur.strands);
  io::write_mesh(out / "gt" / "bald.ply", bald_world);
  io::write_mesh(out / "gt" / "body.glb", bald_world);
  io::write_mesh(out / "gt" / "outer.ply", to_world(envelope.mesh));
  knowledge::write_knowledge(out / "gt" / "knowledge.json", know);
  json region_names = json::array();
  for (auto name : body::kRegionNames) region_names.push_back(std::string(name));
  json shape = json::object();
  for (std::size_t s = 0; s < model.shape_count(); ++s) shape[model.shape_names[s]] = s < params.shape.size() ? params.shape[s] : 0.0f;
  json rotations = json::object();
  for (std::size_t j = 0; j < model.joint_count(); ++j) rotations[model.joint_names[j]] = json_vec3(params.joint_rotations[j]);
  json info{
      {"generator", "nf_gpu synth"},
      {"truth_version", kTruthVersion},
      {"animal", o.animal},
      {"seed", o.seed},
      {"frame", frame.name},
      {"cm_per_unit", kCmPerUnit / frame.scale},
      {"eye_centres", {{"left", json_vec3(glm::vec3(frame.point(glm::dvec3(eyes.left))))}, {"right", json_vec3(glm::vec3(frame.point(glm::dvec3(eyes.right))))}}},
      {"eye_distance_cm", know.eye_distance_cm},
      {"animal_to_world", json_matrix_rows(glm::mat4(frame.matrix() * glm::dmat4(params.animal_to_world)))},
      {"region_names", region_names},
      {"strands", {{"count", fur.strands.strand_count()}, {"points_per_strand", o.points_per_strand},
                   {"length_spread", std::round(1e6 * o.fur_length_spread) / 1e6},
                   {"render_radius", look.radius * frame.scale}}},
      {"body", {{"model", model.name}, {"vertices", bald.vertex_count()}, {"triangles", bald.triangle_count()},
                {"shape", shape}, {"joint_rotations", rotations}, {"torso_length", proportions.torso_length},
                {"proportion_spread", std::round(1e6 * o.proportion_spread) / 1e6}}},
      {"outer", {{"method", "morphological closing of body + strands, then marching cubes"},
                 {"voxel", envelope.voxel * frame.scale}, {"closing_radius", envelope.closing_radius * frame.scale},
                 {"vertices", envelope.mesh.vertex_count()}}},
      {"render", {{"views", o.views}, {"resolution", o.resolution}, {"samples_per_pixel", o.samples_per_axis * o.samples_per_axis},
                  {"shading", o.shading}, {"hair_width", o.hair_width}, {"photo_noise", o.photo_noise}, {"backdrop", o.backdrop}, {"photo_format", o.photo_format}, {"true_orientation", o.true_orientation},
                  {"mean_mask_coverage", coverage_sum / (double(o.views) * o.resolution * o.resolution)}}},
  };
  timings["write_s"] = clock.lap();
  double total = 0;
  for (const auto& [k, v] : timings.items()) total += v.get<double>();
  timings["total_s"] = total;
  info["timings"] = timings;
  write_file_atomic(out / "gt" / "scene.json", info.dump(2) + "\n");

  // Publish: the finished folder replaces an earlier synth output in one rename.
  if (fs::exists(out_dir)) fs::remove_all(out_dir);
  fs::rename(out, out_dir);
  return info;
}

bool truth_is_current(const fs::path& scene) {
  const fs::path file = scene / "gt" / "scene.json";
  if (!fs::exists(file)) return false;
  const json info = io::read_json_file(file);
  if (!info.is_object() || !info.contains("truth_version") || !info["truth_version"].is_number_integer()) return false;
  return info.value("generator", json()) == "nf_gpu synth" && info["truth_version"].get<int>() == kTruthVersion;
}

}  // namespace nf::synth
