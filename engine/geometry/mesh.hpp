#pragma once
// A triangle mesh as the engine shares it. Optional per-vertex normals and region labels
// (regions as small integers, see engine/body/regions.hpp) travel with the geometry. The geometry
// module owns the type; engine/io reads and writes it.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace nf::geometry {

struct Mesh {
  std::vector<float> positions;         // xyz per vertex
  std::vector<std::uint32_t> triangles; // 3 vertex indices per face
  std::vector<float> normals;           // xyz per vertex (empty: absent)
  std::vector<std::int32_t> regions;    // per vertex (empty: absent)

  std::uint64_t vertex_count() const { return positions.size() / 3; }
  std::uint64_t triangle_count() const { return triangles.size() / 3; }
  glm::vec3 position(std::uint64_t v) const { return {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]}; }
  // Throws InputError naming `source` and the inconsistent field (sizes, indices, NaN/Inf).
  void validate(const std::string& source) const;
};

}  // namespace nf::geometry
