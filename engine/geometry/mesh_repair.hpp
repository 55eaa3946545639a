#pragma once
// Repairs for meshes extracted from grids before other stages build on them: faces that repeat a
// vertex or have no area, duplicated faces, edges shared by more than two faces, small holes,
// small components; and decimation to a face budget (Debian's meshoptimizer, edge collapses under a
// quadric error metric that keep the topology).
#include <cstdint>

#include "engine/core/json.hpp"
#include "engine/geometry/mesh.hpp"

namespace nf::geometry {

struct RepairReport {
  std::uint64_t degenerate_faces = 0;   // a repeated vertex or zero area
  std::uint64_t duplicate_faces = 0;    // the same three vertices as an earlier face
  std::uint64_t non_manifold_faces = 0; // removed: on an edge used by more than two faces
  std::uint64_t holes_filled = 0, holes_left = 0;  // boundary loops closed / too long to close
  std::uint64_t components_dropped = 0;
};
json to_json(const RepairReport& report);

// In place: drops degenerate and duplicate faces and every face on an edge used more than twice,
// closes boundary loops of at most `max_hole_edges` edges with a fan around their centroid (the
// new vertex takes the most common region of the loop), keeps the largest component and drops
// unused vertices. Normals are recomputed when present.
RepairReport repair_mesh(Mesh& mesh, std::uint32_t max_hole_edges);

struct DecimateReport {
  std::uint64_t faces_before = 0, faces_after = 0;
  double error = 0;  // meshoptimizer's error estimate, scene units
};

// Edge collapses down to about `target_faces` (nothing happens when the mesh has fewer). Regions
// and normals follow their vertices (normals are recomputed).
DecimateReport decimate(Mesh& mesh, std::uint64_t target_faces);

}  // namespace nf::geometry
