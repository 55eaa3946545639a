#include "engine/geometry/mesh.hpp"

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"

namespace nf::geometry {

void Mesh::validate(const std::string& source) const {
  if (positions.size() % 3) throw InputError(source + ": vertex positions are not xyz triples");
  if (triangles.size() % 3) throw InputError(source + ": face indices are not triples");
  const std::uint64_t n = vertex_count();
  for (std::size_t i = 0; i < triangles.size(); ++i)
    if (triangles[i] >= n)
      throw InputError(source + ": face " + std::to_string(i / 3) + " uses vertex " + std::to_string(triangles[i]) +
                       " of " + std::to_string(n));
  if (!normals.empty() && normals.size() != positions.size()) throw InputError(source + ": normals do not match the vertices");
  if (!regions.empty() && regions.size() != n) throw InputError(source + ": regions do not match the vertices");
  require_finite(positions, source + ": vertex positions");
  require_finite(normals, source + ": vertex normals");
}

}  // namespace nf::geometry
