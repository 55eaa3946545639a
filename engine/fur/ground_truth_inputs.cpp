#include "engine/fur/ground_truth_inputs.hpp"

#include <algorithm>
#include <cmath>

#include "engine/core/error.hpp"
#include "engine/defur/sdf_file.hpp"
#include "engine/defur/vertex_fur.hpp"
#include "engine/geometry/mesh_sdf.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/geometry/point_index.hpp"
#include "engine/geometry/surface_sampling.hpp"
#include "engine/geometry/tangent_field.hpp"
#include "engine/io/ground_truth.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/view_split.hpp"
#include "engine/knowledge/knowledge.hpp"

namespace nf::fur {
namespace fs = std::filesystem;

void set_surface_inputs(FurTrainingData& data, const geometry::Mesh& outer, const std::function<bool(std::int32_t)>& grows, unsigned seed) {
  const geometry::SurfaceSamples samples = geometry::sample_surface(outer, 200000, seed);
  data.surface_points.clear();
  if (outer.regions.size() == outer.vertex_count() && grows) {
    const geometry::PointIndex index(outer.positions);
    for (std::size_t i = 0; i < samples.points.size() / 3; ++i)
      if (grows(outer.regions[index.nearest(&samples.points[3 * i]).first]))
        data.surface_points.insert(data.surface_points.end(), &samples.points[3 * i], &samples.points[3 * i] + 3);
  } else {
    data.surface_points = samples.points;
  }
  const geometry::Bounds b = geometry::mesh_bounds(outer);
  const float longest = data.roots.size() ? *std::max_element(data.roots.length.begin(), data.roots.length.end()) : 0.f;
  data.lo = b.lo - glm::vec3(longest), data.hi = b.hi + glm::vec3(longest);
  data.scene_radius = 0.5 * double(glm::length(b.hi - b.lo));
  // M_NeuS's signed distance, negated (positive inside): the penetration kernel on it penalises
  // strand points beyond M_NeuS. The band reaches the longest strand at the default largest
  // length factor (LengthFactorBounds: 2.5), so a tip anywhere outside is pulled back (beyond the
  // band the distance is clamped and pulls no more).
  geometry::SdfOptions sdf_options;
  sdf_options.resolution = 128;
  sdf_options.band = float(LengthFactorBounds{}.hi) * longest + 3.f * b.longest() / float(sdf_options.resolution - 1);
  const geometry::SignedDistanceGrid sdf = geometry::signed_distance_grid(outer, sdf_options, "M_NeuS");
  data.envelope_sdf = {sdf.grid, sdf.band, sdf.distance};
  for (float& v : data.envelope_sdf.values) v = -v;
}

GroundTruthInputs ground_truth_inputs(gpu::Context& gpu, const fs::path& scene_dir, const GroundTruthInputOptions& o) {
  const std::optional<io::GroundTruth> gt = io::find_ground_truth(scene_dir);
  if (!gt) throw InputError(scene_dir.string() + ": no ground truth (gt/scene.json); only `nf_gpu synth` scenes have one");
  GroundTruthInputs in;
  in.bald = o.bald ? *o.bald : io::read_mesh(gt->bald());
  in.outer = io::read_mesh(gt->outer());
  if (in.bald.regions.size() != in.bald.vertex_count())
    throw InputError((o.bald ? std::string("the bald body given") : gt->bald().string()) + ": no region per vertex");
  const knowledge::Knowledge know = knowledge::read_knowledge(gt->knowledge());
  glm::mat3 animal_to_world(1.f);
  try {
    const json& rows = gt->info.at("animal_to_world");
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) animal_to_world[c][r] = rows.at(std::size_t(r)).at(std::size_t(c)).get<float>();
  } catch (const json::exception& e) {
    throw InputError(gt->scene_json().string() + ": animal_to_world: " + e.what());
  }
  std::array<glm::vec3, body::kRegionCount> directions{};
  for (int r = 0; r < body::kRegionCount; ++r)
    if (know.has(body::Region(r))) {
      const float e = float(o.heading_error_deg * M_PI / 180.0);
      const glm::vec3 a = know.at(body::Region(r)).direction;  // animal frame: y up
      const glm::vec3 turned(std::cos(e) * a.x + std::sin(e) * a.z, a.y, -std::sin(e) * a.x + std::cos(e) * a.z);
      const glm::vec3 d = animal_to_world * turned;
      directions[std::size_t(r)] = glm::length(d) > 0 ? glm::normalize(d) : d;
    }
  const double cm = gt->cm_per_unit;
  in.vertex_fur = defur::vertex_fur(in.bald, know, directions, cm, 20);
  const defur::VertexFur& vertex_fur = in.vertex_fur;

  geometry::TangentFieldOptions field_options;
  field_options.smoothing_length = o.smoothing_cm / cm;
  const geometry::TangentField field = geometry::smooth_tangent_field(in.bald, face_growth_guides(in.bald, vertex_fur), field_options);
  FurTrainingData& data = in.data;
  in.frames = {field.tangent, field.normal};
  data.roots = sample_roots(in.bald, in.frames, vertex_fur, o.roots, o.seed);
  data.cm_per_unit = cm;
  data.fur_area = fur_area(in.bald, vertex_fur);

  data.bald_sdf = defur::bald_body_sdf(in.bald, o.sdf_resolution, gt->bald().string());
  set_surface_inputs(data, in.outer, {}, o.seed);

  const io::Scene scene = o.make_views ? io::read_scene(scene_dir) : io::Scene{};
  for (std::uint32_t v = 0; o.make_views && v < scene.cameras.size(); ++v) {
    const bool held = io::is_held_out(v, o.hold_out_every);
    (held ? data.held_out : data.train).push_back(make_fur_view(gpu, scene, v, nullptr, in.bald, o.views));
  }
  return in;
}

}  // namespace nf::fur
