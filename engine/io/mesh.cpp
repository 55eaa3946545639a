#include "engine/io/mesh.hpp"

#include "engine/core/error.hpp"

namespace nf::io {

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
