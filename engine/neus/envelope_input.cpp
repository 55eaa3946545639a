#include "engine/neus/envelope_input.hpp"

#include <cstdio>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/io/mesh.hpp"

namespace nf::neus {
namespace fs = std::filesystem;

json to_json(const EnvelopeInputReport& r) {
  return {{"vertices", r.vertices},
          {"triangles", r.triangles},
          {"inside_hull", r.inside_hull},
          {"extent_ratio", r.extent_ratio},
          {"flipped", r.flipped}};
}

namespace {

std::string percent(double share) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f %%", 100.0 * share);
  return text;
}

// The volume the faces enclose, by the divergence theorem about the box centre; negative when they
// face inwards. Taken about the centre, not the scene origin, so that a mesh far from the origin
// keeps its precision and the holes of an open scan add little (each adds its cone to the centre).
double enclosed_volume(const geometry::Mesh& m) {
  const geometry::Bounds box = geometry::mesh_bounds(m);
  const glm::dvec3 centre = 0.5 * (glm::dvec3(box.lo) + glm::dvec3(box.hi));
  double v = 0;
  for (std::uint64_t t = 0; t < m.triangle_count(); ++t) {
    const glm::dvec3 a = glm::dvec3(m.position(m.triangles[3 * t])) - centre, b = glm::dvec3(m.position(m.triangles[3 * t + 1])) - centre,
                     c = glm::dvec3(m.position(m.triangles[3 * t + 2])) - centre;
    v += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return v;
}

// The share of the surface area whose face centres lie in the grid's occupied cells: a few huge
// faces (a floor) weigh what they cover, not their four vertices.
double area_share_inside(const geometry::Mesh& m, const OccupancyGrid& grid) {
  double inside = 0, total = 0;
  for (std::uint64_t t = 0; t < m.triangle_count(); ++t) {
    const glm::dvec3 a = m.position(m.triangles[3 * t]), b = m.position(m.triangles[3 * t + 1]), c = m.position(m.triangles[3 * t + 2]);
    const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
    total += area;
    if (grid.contains((a + b + c) / 3.0)) inside += area;
  }
  return total > 0 ? inside / total : 0.0;
}

}  // namespace

geometry::Mesh read_envelope_input(const fs::path& file, EnvelopeInputReport* report) {
  const std::string where = "neus.mesh=" + file.string();
  geometry::Mesh mesh = io::read_mesh(file);
  mesh.validate(file.string());
  if (mesh.triangle_count() == 0)
    throw InputError(where + ": the mesh has no faces (a point cloud cannot stand for the fur's envelope)");
  mesh.regions.clear();
  report->vertices = mesh.vertex_count(), report->triangles = mesh.triangle_count();
  report->flipped = enclosed_volume(mesh) < 0;
  if (report->flipped) {  // later stages read outward normals (body fit, defur)
    for (std::uint64_t t = 0; t < mesh.triangle_count(); ++t) std::swap(mesh.triangles[3 * t + 1], mesh.triangles[3 * t + 2]);
    log::warn(where, ": its faces pointed inwards; turned them outwards");
  }
  // A file's normals need not agree with its winding: the winding, now outwards, decides.
  if (!mesh.normals.empty()) geometry::compute_vertex_normals(mesh);
  return mesh;
}

void check_envelope_against_hull(const geometry::Mesh& mesh, const OccupancyGrid& hull, const fs::path& file,
                                 EnvelopeInputReport* report) {
  const std::string where = "neus.mesh=" + file.string();
  // The hull keeps every cell that may project into a mask; two cells of slack absorb a scan's
  // registration error against the cameras.
  report->inside_hull = area_share_inside(mesh, dilate(hull, 2));
  glm::dvec3 lo, hi;
  hull.occupied_bounds(lo, hi);
  report->extent_ratio = double(geometry::mesh_bounds(mesh).diagonal()) / glm::length(hi - lo);
  const std::string frame_hint = ": it must be in the scene's world frame and units, the frame its cameras are in";
  if (report->inside_hull < kMinEnvelopeInsideHull)
    throw InputError(where + ": only " + percent(report->inside_hull) + " of its surface lies inside the visual hull of the masks (at least " +
                     percent(kMinEnvelopeInsideHull) + " needed)" + frame_hint + ", holding the animal only (no floor or stand)");
  if (report->extent_ratio < kMinEnvelopeExtentRatio || report->extent_ratio > kMaxEnvelopeExtentRatio)
    throw InputError(where + ": its box spans " + percent(report->extent_ratio) + " of the masks' visual hull (" +
                     percent(kMinEnvelopeExtentRatio) + " to " + percent(kMaxEnvelopeExtentRatio) + " needed)" + frame_hint +
                     ", covering the whole animal and nothing far from it");
}

}  // namespace nf::neus
