#pragma once
// De-furring (paper: De-furring; supplementary: De-furring process): the bald body M_bald from the
// fur's outer surface M_NeuS by moving it inwards by the fur's thickness,
//     SDF_defur(x) = SDF(x) + s(x),
// with SDF the signed distance to M_NeuS (geometry/mesh_sdf.hpp: winding-number sign, exact banded
// distance) and s the thickness of the fur at the closest point of M_NeuS: each vertex takes its
// region's thickness, smoothed over the mesh (uniform Laplacian, as the public code's 100
// iterations) so region borders do not step, and s interpolates the closest triangle's vertices.
// Its zero set is extracted by the GPU marching cubes, repaired (geometry/mesh_repair.hpp) and
// decimated to a face budget.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/json.hpp"
#include "engine/geometry/mesh.hpp"
#include "engine/geometry/mesh_repair.hpp"
#include "engine/geometry/mesh_sdf.hpp"
#include "engine/knowledge/knowledge.hpp"

namespace nf::gpu {
class Context;
}

namespace nf::defur {

// Per-vertex fur thickness of a labelled mesh in scene units (region thickness in cm divided by
// cm_per_unit; 0 for a region without an entry), smoothed by `iterations` Laplacian steps.
// InputError when the mesh has no regions or cm_per_unit is not positive.
std::vector<float> vertex_thickness(const geometry::Mesh& labelled, const knowledge::Knowledge& knowledge,
                                    double cm_per_unit, int iterations, const std::string& source);

struct DefurOptions {
  int resolution = 256;                // grid samples along M_NeuS's longest side
  std::uint64_t target_faces = 160000; // decimation budget (a coarser extraction is kept as it is)
  std::uint32_t max_hole_edges = 100;  // longer boundary loops stay open
  int thickness_smoothing = 100;       // Laplacian iterations of the per-vertex thickness
  double cm_per_unit = 0;              // the metric scale (knowledge stage)
};

struct RegionDepth {
  std::int32_t region = 0;
  double thickness = 0;  // the region's largest smoothed thickness, scene units
  double depth = 0;      // the deepest point inside M_NeuS whose closest surface is the region's (capped by the band)
  bool vanishes = false; // thickness >= depth: the region leaves nothing behind
};

struct DefurResult {
  geometry::Mesh bald;  // normals, no regions
  geometry::RepairReport outer_repair;  // M_NeuS cleaned first: stray, duplicated and non-manifold faces would carve
  geometry::GridSpec grid;
  float band = 0;
  geometry::SignStats sign;
  std::uint64_t extracted_faces = 0;
  geometry::RepairReport repair;
  geometry::DecimateReport decimation;
  std::vector<RegionDepth> regions;  // regions present on M_NeuS
  json seconds = json::object();     // per step
};

// outer: M_NeuS with a region per vertex. It is repaired first (geometry/mesh_repair.hpp: a face
// stuck into the body or a duplicated sheet would otherwise carve the shrunken surface), then each
// vertex takes its region's thickness (vertex_thickness). InputError naming the regions when the
// bald body would vanish (nothing, or a small piece, is left).
DefurResult defur_surface(gpu::Context& gpu, const geometry::Mesh& outer, const knowledge::Knowledge& knowledge,
                          const DefurOptions& options, const std::string& source);

json to_json(const DefurResult& result);

}  // namespace nf::defur
