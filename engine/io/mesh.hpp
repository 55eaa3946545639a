#pragma once
// Mesh files: PLY, OBJ and glTF readers and writers of geometry::Mesh.
#include <filesystem>
#include <span>

#include "engine/geometry/mesh.hpp"
#include "engine/io/file_frame.hpp"
#include "engine/io/skeleton.hpp"

namespace nf::io {

using geometry::Mesh;  // io reads and writes the geometry module's mesh

// PLY: reads ASCII and binary little-endian files (vertex x y z, optional nx ny nz and an integer
// region / label property; faces as vertex_indices lists, polygons fanned into triangles); writes
// binary little-endian with normals and regions when present.
Mesh read_mesh_ply(const std::filesystem::path& path);
void write_mesh_ply(const std::filesystem::path& path, const Mesh& mesh);

// OBJ: v, vn and f (polygons fanned; v/vt/vn forms accepted); regions are not stored.
Mesh read_mesh_obj(const std::filesystem::path& path);
void write_mesh_obj(const std::filesystem::path& path, const Mesh& mesh);

// glTF 2.0, parsed and written by tinygltf. The reader takes .glb and .gltf (buffers in the GLB BIN
// chunk, in external files relative to the .gltf, or in base64 data: URIs, holding exactly byteLength
// bytes). It flattens the default scene (scenes[0] when
// `scene` is unset; every mesh once, untransformed, when there are no scenes): node transforms
// (matrix or TRS) are applied to positions and normals (inverse transpose; winding flipped under a
// mirroring transform), and all primitives are merged into one mesh. Modes TRIANGLES, TRIANGLE_STRIP
// and TRIANGLE_FAN become triangles, POINTS adds its vertices without faces, LINES / LINE_LOOP /
// LINE_STRIP and primitives without POSITION are skipped with a logged warning. Indexed (u8, u16,
// u32) and non-indexed primitives, byteStride and byte offsets are read. POSITION and NORMAL must be
// FLOAT VEC3; the custom attribute _REGION (SCALAR: FLOAT holding integers, or BYTE, UNSIGNED_BYTE,
// SHORT, UNSIGNED_SHORT, UNSIGNED_INT) becomes the regions. Normals / regions are kept only when
// every merged primitive has them. Refused with an InputError naming the file and the field:
// sparse accessors, accessors without a bufferView, quantized / Draco / meshopt geometry, non-file
// URIs (http:), and any count, offset, stride or index out of range, NaN / Inf values, malformed
// GLB chunks, JSON nested deeper than 256 levels, and sections that tinygltf cannot parse (images,
// materials, cameras... are parsed though not used; images are never decoded). Morph targets, skins
// and instancing extensions are ignored.
// The writer produces GLB only (one scene / node / mesh / primitive; POSITION with min / max,
// NORMAL, _REGION as FLOAT SCALAR, which Blender imports as a generic attribute, so regions must
// lie within +-2^24; indices UNSIGNED_INT; a mesh without faces is written as POINTS, an empty mesh
// without a scene). Writing
// .gltf through write_mesh is refused: use .glb.
// With a skeleton, the vertices also get JOINTS_0 (UNSIGNED_SHORT) and WEIGHTS_0, the joints become
// a node hierarchy (translations only; the bind pose is the mesh as given) and a skin binds them
// with inverse bind matrices, so Blender and Unreal import an armature that poses the mesh.
// read_skeleton_gltf reads such a file's first skin back (joint names, parents, bind positions,
// the first primitive's influences); InputError when the file has no skin or it is malformed.
Mesh read_mesh_gltf(const std::filesystem::path& path);
// `frame` is stated in the asset's generator (file_frame.hpp). `vertex_colors` (linear RGB per
// vertex in [0, 1] as glTF requires, or empty) become COLOR_0 (FLOAT VEC3), which Blender imports
// as a colour attribute.
void write_mesh_glb(const std::filesystem::path& path, const Mesh& mesh, const Skeleton* skeleton = nullptr, FileFrame frame = FileFrame::scene,
                    std::span<const float> vertex_colors = {});
Skeleton read_skeleton_gltf(const std::filesystem::path& path);

// By extension (.ply, .obj, .glb, .gltf).
Mesh read_mesh(const std::filesystem::path& path);
void write_mesh(const std::filesystem::path& path, const Mesh& mesh);

}  // namespace nf::io
