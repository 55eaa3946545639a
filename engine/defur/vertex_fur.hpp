#pragma once
// The knowledge per vertex of M_bald: region (from the body re-fitted to M_bald), fur length in
// scene units and growth direction in world coordinates, both smoothed across region borders among
// the vertices that grow fur. A vertex of a region without fur (no entry or zero length) is bald:
// length 0, direction 0, and it takes no part in its neighbours' smoothing.
#include <array>
#include <filesystem>
#include <vector>

#include <glm/glm.hpp>

#include "engine/body/regions.hpp"
#include "engine/geometry/mesh.hpp"
#include "engine/knowledge/knowledge.hpp"

namespace nf::defur {

struct VertexFur {
  std::vector<std::int32_t> region;
  std::vector<float> length;          // scene units; 0: bald
  std::vector<glm::vec3> direction;   // unit, world; 0 where bald
  std::size_t size() const { return region.size(); }
  bool grows(std::size_t v) const { return length[v] > 0; }
};

// mesh.regions must hold a region per vertex. directions_world: the regions' growth directions in
// world coordinates (knowledge stage's directions_world.json).
VertexFur vertex_fur(const geometry::Mesh& mesh, const knowledge::Knowledge& knowledge,
                     const std::array<glm::vec3, body::kRegionCount>& directions_world, double cm_per_unit,
                     int smoothing_iterations);

// vertex_fur.npz: region (i4), length (f4, scene units), direction (f4, n x 3). The reader checks
// shapes, region ids, finite values and the vertex count it expects, naming the file and array.
void write_vertex_fur(const std::filesystem::path& file, const VertexFur& fur);
VertexFur read_vertex_fur(const std::filesystem::path& file, std::size_t vertex_count);

}  // namespace nf::defur
