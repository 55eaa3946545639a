#pragma once
// A triangle mesh as the engine and the mesh files share it. Optional per-vertex normals and
// region labels (DESIGN §5 regions, as small integers) travel with the geometry.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace nf::io {

struct Mesh {
  std::vector<float> positions;         // xyz per vertex
  std::vector<std::uint32_t> triangles; // 3 vertex indices per face
  std::vector<float> normals;           // xyz per vertex (empty: absent)
  std::vector<std::int32_t> regions;    // per vertex (empty: absent)

  std::uint64_t vertex_count() const { return positions.size() / 3; }
  std::uint64_t triangle_count() const { return triangles.size() / 3; }
  // Throws InputError naming `source` and the inconsistent field (sizes, indices, NaN/Inf).
  void validate(const std::string& source) const;
};

// PLY: reads ASCII and binary little-endian files (vertex x y z, optional nx ny nz and an integer
// region / label property; faces as vertex_indices lists, polygons fanned into triangles); writes
// binary little-endian with normals and regions when present.
Mesh read_mesh_ply(const std::filesystem::path& path);
void write_mesh_ply(const std::filesystem::path& path, const Mesh& mesh);

// OBJ: v, vn and f (polygons fanned; v/vt/vn forms accepted); regions are not stored.
Mesh read_mesh_obj(const std::filesystem::path& path);
void write_mesh_obj(const std::filesystem::path& path, const Mesh& mesh);

// By extension (.ply, .obj).
Mesh read_mesh(const std::filesystem::path& path);
void write_mesh(const std::filesystem::path& path, const Mesh& mesh);

}  // namespace nf::io
