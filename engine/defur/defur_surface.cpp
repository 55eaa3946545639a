#include "engine/defur/defur_surface.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "engine/body/regions.hpp"
#include "engine/core/error.hpp"
#include "engine/core/stopwatch.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/closest_point.hpp"
#include "engine/geometry/marching_cubes_gpu.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/geometry/vertex_smoothing.hpp"

namespace nf::defur {
namespace {

std::string in_cm(double units, double cm_per_unit) {
  std::ostringstream s;
  s.precision(3);
  if (cm_per_unit > 0) s << units * cm_per_unit << " cm";
  else s << units << " scene units";
  return s.str();
}

}  // namespace

std::vector<float> vertex_thickness(const geometry::Mesh& labelled, const knowledge::Knowledge& knowledge, double cm_per_unit,
                                    int iterations, const std::string& source) {
  if (labelled.regions.size() != labelled.vertex_count())
    throw InputError(source + ": the mesh has no region per vertex (run the body stage)");
  if (!(cm_per_unit > 0) || !std::isfinite(cm_per_unit))
    throw InputError(source + ": the metric scale must be a positive number of cm per scene unit");
  std::vector<float> s(labelled.vertex_count(), 0.f);
  for (std::size_t v = 0; v < s.size(); ++v) {
    const std::int32_t r = labelled.regions[v];
    if (r < 0 || r >= body::kRegionCount) throw InputError(source + ": vertex " + std::to_string(v) + " has region id " + std::to_string(r) + ", outside the table");
    if (knowledge.has(body::Region(r))) s[v] = float(knowledge.at(body::Region(r)).thickness_cm / cm_per_unit);
  }
  geometry::smooth_vertex_values(labelled, s, 1, iterations);
  return s;
}

DefurResult defur_surface(gpu::Context& gpu, const geometry::Mesh& labelled, const knowledge::Knowledge& knowledge,
                          const DefurOptions& options, const std::string& source) {
  labelled.validate(source);
  if (labelled.regions.size() != labelled.vertex_count())
    throw InputError(source + ": the mesh has no region per vertex (run the body stage)");
  DefurResult result;
  Stopwatch t;
  geometry::Mesh outer = labelled;
  result.outer_repair = geometry::repair_mesh(outer, options.max_hole_edges);
  if (outer.triangle_count() == 0) throw InputError(source + ": no usable faces");
  const std::vector<float> thickness = vertex_thickness(outer, knowledge, options.cm_per_unit, options.thickness_smoothing, source);
  result.seconds["clean_and_thickness"] = t.seconds();
  t.restart();
  const float max_s = thickness.empty() ? 0.f : *std::max_element(thickness.begin(), thickness.end());
  const double diagonal = geometry::mesh_bounds(outer).diagonal();  // its main part: the repair kept the largest component
  geometry::SdfOptions sdf_options;
  sdf_options.resolution = options.resolution;
  {
    // The band holds the shrunken surface with room for the extraction around it.
    const float longest = geometry::mesh_bounds(outer).longest();
    const float voxel = longest / float(std::max(options.resolution - 1, 1));
    // Nothing lies deeper than half the longest side: a thicker fur needs no wider band (and is
    // refused below, naming its region).
    sdf_options.band = std::min(max_s, 0.5f * longest) + 3 * voxel;
  }
  const geometry::SignedDistanceGrid sdf = geometry::signed_distance_grid(outer, sdf_options, source);
  result.grid = sdf.grid, result.band = sdf.band, result.sign = sdf.sign;
  result.seconds["sdf"] = t.seconds();

  t.restart();
  const geometry::GridSpec& g = sdf.grid;
  std::vector<float> field(g.size());
  std::vector<std::uint8_t> nearest_region(g.size(), 255);
  parallel_for(std::size_t(g.dims.z), [&](std::size_t k0, std::size_t k1) {
    for (std::size_t k = k0; k < k1; ++k)
      for (int j = 0; j < g.dims.y; ++j)
        for (int i = 0; i < g.dims.x; ++i) {
          const std::size_t n = g.index(i, j, int(k));
          const std::uint32_t tri = sdf.closest[n];
          if (tri == geometry::kNoTriangle) {
            field[n] = sdf.distance[n];
            continue;
          }
          const std::uint32_t* v = &outer.triangles[3 * std::size_t(tri)];
          const geometry::TrianglePoint cp = geometry::closest_point_on_triangle(g.position(i, j, int(k)), outer.position(v[0]),
                                                                                 outer.position(v[1]), outer.position(v[2]));
          const glm::vec3& b = cp.barycentric;
          field[n] = sdf.distance[n] + b.x * thickness[v[0]] + b.y * thickness[v[1]] + b.z * thickness[v[2]];
          const int m = b.x >= b.y && b.x >= b.z ? 0 : b.y >= b.z ? 1 : 2;
          if (sdf.distance[n] < 0) nearest_region[n] = std::uint8_t(outer.regions[v[m]]);
        }
  }, 1);
  std::array<double, body::kRegionCount> depth{}, region_thickness{};
  std::array<bool, body::kRegionCount> present{};
  for (std::size_t v = 0; v < outer.vertex_count(); ++v) {
    const std::size_t r = std::size_t(outer.regions[v]);
    present[r] = true, region_thickness[r] = std::max(region_thickness[r], double(thickness[v]));
  }
  for (std::size_t n = 0; n < g.size(); ++n)
    if (nearest_region[n] != 255) depth[nearest_region[n]] = std::max(depth[nearest_region[n]], double(-sdf.distance[n]));
  for (int r = 0; r < body::kRegionCount; ++r)
    if (present[std::size_t(r)])
      result.regions.push_back({r, region_thickness[std::size_t(r)], depth[std::size_t(r)],
                                region_thickness[std::size_t(r)] > 0 && region_thickness[std::size_t(r)] >= depth[std::size_t(r)]});
  result.seconds["shrink"] = t.seconds();

  t.restart();
  result.bald = geometry::marching_cubes_gpu(gpu, field, g.dims, g.origin, glm::vec3(g.voxel), 0.f);
  result.extracted_faces = result.bald.triangle_count();
  result.seconds["marching_cubes"] = t.seconds();

  t.restart();
  if (result.bald.triangle_count() > 0) result.repair = geometry::repair_mesh(result.bald, options.max_hole_edges);
  result.seconds["repair"] = t.seconds();
  const double kept = geometry::mesh_bounds(result.bald).diagonal();
  if (!(kept >= 0.5 * diagonal)) {
    std::vector<RegionDepth> culprits;
    for (const RegionDepth& r : result.regions)
      if (r.vanishes) culprits.push_back(r);
    if (culprits.empty())  // the thickest relative to its depth
      culprits.push_back(*std::max_element(result.regions.begin(), result.regions.end(), [](const RegionDepth& a, const RegionDepth& b) {
        return a.thickness / std::max(a.depth, 1e-30) < b.thickness / std::max(b.depth, 1e-30);
      }));
    std::string what;
    for (const RegionDepth& r : culprits)
      what += (what.empty() ? "" : "; ") + std::string("region '") + body::region_name(r.region) + "': thickness " +
              in_cm(r.thickness, options.cm_per_unit) + ", but the animal is only " + in_cm(r.depth, options.cm_per_unit) +
              " deep there";
    throw InputError(source + ": de-furring would leave " + (result.bald.triangle_count() == 0 ? "nothing" : "only a small piece") +
                     " of the body: " + what + ". Lower thickness_cm in the knowledge (knowledge.json) or check the metric scale");
  }

  t.restart();
  result.decimation = geometry::decimate(result.bald, options.target_faces);
  if (result.decimation.faces_after < result.decimation.faces_before) {
    // Edge collapses can pinch a vertex or fold a sliver: repair once more.
    const geometry::RepairReport again = geometry::repair_mesh(result.bald, options.max_hole_edges);
    result.repair.degenerate_faces += again.degenerate_faces, result.repair.duplicate_faces += again.duplicate_faces;
    result.repair.non_manifold_faces += again.non_manifold_faces, result.repair.holes_filled += again.holes_filled;
    result.repair.holes_left += again.holes_left, result.repair.components_dropped += again.components_dropped;
  }
  geometry::compute_vertex_normals(result.bald);
  result.seconds["decimate"] = t.seconds();
  return result;
}

json to_json(const DefurResult& r) {
  json regions = json::object();
  for (const RegionDepth& d : r.regions)
    regions[body::region_name(d.region)] = {{"thickness", d.thickness}, {"depth", d.depth}, {"vanishes", d.vanishes}};
  return {{"outer_repair", geometry::to_json(r.outer_repair)},
          {"grid", {{"dims", {r.grid.dims.x, r.grid.dims.y, r.grid.dims.z}}, {"voxel", r.grid.voxel}, {"band", r.band}}},
          {"sign", {{"lines", r.sign.lines}, {"open_lines", r.sign.open_lines}, {"tied_samples", r.sign.tied_samples}}},
          {"extracted_faces", r.extracted_faces},
          {"repair", geometry::to_json(r.repair)},
          {"decimation", {{"faces_before", r.decimation.faces_before}, {"faces_after", r.decimation.faces_after},
                          {"error", r.decimation.error}}},
          {"faces", r.bald.triangle_count()},
          {"vertices", r.bald.vertex_count()},
          {"regions", regions},
          {"seconds", r.seconds}};
}

}  // namespace nf::defur
