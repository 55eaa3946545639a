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

// The volume the faces enclose, by the divergence theorem; negative when they face inwards. On an
// open mesh it is the volume of the cone to the origin, which keeps its sign for a scan with holes.
double enclosed_volume(const geometry::Mesh& m) {
  double v = 0;
  for (std::uint64_t t = 0; t < m.triangle_count(); ++t) {
    const glm::dvec3 a = m.position(m.triangles[3 * t]), b = m.position(m.triangles[3 * t + 1]), c = m.position(m.triangles[3 * t + 2]);
    v += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return v;
}

}  // namespace

geometry::Mesh read_envelope_input(const fs::path& file, const OccupancyGrid& hull, EnvelopeInputReport* report) {
  const std::string where = "neus.mesh " + file.string();
  if (!fs::is_regular_file(file)) throw InputError(where + ": no such file");
  geometry::Mesh mesh = io::read_mesh(file);
  mesh.validate(file.string());
  if (mesh.triangle_count() == 0)
    throw InputError(where + ": the mesh has no faces (a point cloud cannot stand for the fur's envelope)");
  mesh.regions.clear();

  EnvelopeInputReport r;
  r.vertices = mesh.vertex_count(), r.triangles = mesh.triangle_count();
  // The hull keeps every cell that may project into a mask; two cells of slack absorb a scan's
  // registration error against the cameras.
  const OccupancyGrid grown = dilate(hull, 2);
  std::uint64_t inside = 0;
  for (std::uint64_t v = 0; v < mesh.vertex_count(); ++v) inside += grown.contains(glm::dvec3(mesh.position(v))) ? 1 : 0;
  r.inside_hull = double(inside) / double(mesh.vertex_count());
  glm::dvec3 lo, hi;
  hull.occupied_bounds(lo, hi);
  r.extent_ratio = double(geometry::mesh_bounds(mesh).diagonal()) / glm::length(hi - lo);
  const std::string frame_hint = ": it must be in the scene's world frame and units, the frame its cameras are in";
  if (r.inside_hull < kMinEnvelopeInsideHull)
    throw InputError(where + ": only " + percent(r.inside_hull) + " of its vertices lie inside the visual hull of the masks (at least " +
                     percent(kMinEnvelopeInsideHull) + " needed)" + frame_hint + ", holding the animal only (no floor or stand)");
  if (r.extent_ratio < kMinEnvelopeExtentRatio)
    throw InputError(where + ": its box spans " + percent(r.extent_ratio) + " of the masks' visual hull (at least " +
                     percent(kMinEnvelopeExtentRatio) + " needed)" + frame_hint + ", covering the whole animal");

  if (enclosed_volume(mesh) < 0) {  // later stages read outward normals (body fit, defur)
    for (std::uint64_t t = 0; t < mesh.triangle_count(); ++t) std::swap(mesh.triangles[3 * t + 1], mesh.triangles[3 * t + 2]);
    for (float& n : mesh.normals) n = -n;
    r.flipped = true;
    log::warn(where, ": its faces pointed inwards; turned them outwards");
  }
  if (report) *report = r;
  return mesh;
}

}  // namespace nf::neus
