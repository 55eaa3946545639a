#pragma once
// A glTF 2.0 file (.glb, or .gltf with its buffers) parsed by tinygltf into a tinygltf::Model whose
// geometry fields the mesh reader can trust: every field it uses has the right type and every index
// it follows from a primitive is in range. The buffers' bytes are loaded; their byte ranges
// (bufferViews, accessors) are the mesh reader's to check.
#include <filesystem>

#include "engine/io/tinygltf.hpp"

namespace nf::io {

// Throws InputError naming the file and the field (e.g. "accessors[0].count is 1.5, not a
// non-negative integer"): a malformed GLB container or JSON, wrong types, indices out of range,
// sparse or compressed geometry, buffer URIs that are not relative files or base64 data: URIs
// (nothing is downloaded), missing or short buffer files.
tinygltf::Model load_gltf_model(const std::filesystem::path& path);

}  // namespace nf::io
