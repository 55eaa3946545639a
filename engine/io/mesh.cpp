#include "engine/io/mesh.hpp"

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"

namespace nf::io {

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

Mesh read_mesh(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".ply") return read_mesh_ply(path);
  if (ext == ".obj") return read_mesh_obj(path);
  if (ext == ".glb" || ext == ".gltf") return read_mesh_gltf(path);
  throw InputError(path.string() + ": unknown mesh format '" + ext + "' (.ply, .obj, .glb, .gltf)");
}

void write_mesh(const std::filesystem::path& path, const Mesh& mesh) {
  const std::string ext = path.extension().string();
  if (ext == ".ply") return write_mesh_ply(path, mesh);
  if (ext == ".obj") return write_mesh_obj(path, mesh);
  if (ext == ".glb") return write_mesh_glb(path, mesh);
  if (ext == ".gltf")
    throw InputError(path.string() + ": .gltf is not written; use .glb (binary glTF, the same content in one file)");
  throw InputError(path.string() + ": unknown mesh format '" + ext + "' (.ply, .obj, .glb)");
}

}  // namespace nf::io
