#pragma once
// The frame a geometry file's coordinates are in, written by nf_gpu into every strand and mesh file
// (the .hair info field, a PLY or OBJ comment, the USD layer's doc, the glTF generator) so that a
// command reading two files can tell: the scene's frame (its cameras' world and unit) or the export
// frame (metres, +y up, the animal facing +z; the export.json beside the file holds the map).
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

namespace nf::io {

enum class FileFrame { unknown, scene, exported };

// The words nf_gpu writes into a file: "nf_gpu frame: scene" or "nf_gpu frame: export".
std::string_view frame_marker(FileFrame frame);
// For messages: "the scene's frame", "the export frame (metres, +y up)", "no stated frame".
std::string frame_words(FileFrame frame);
// What the file says, or for an older file the export.json beside it that lists it (unknown for a
// file nf_gpu did not write).
FileFrame declared_frame(const std::filesystem::path& file);

// Brings files into one frame before they are compared or drawn together. Each file's matrix maps
// its points into the common frame: the scene's, unless every file is in the export frame and
// `scene_required` is false (a scene's cameras draw them: render). An export-frame file goes back into the scene's frame through its export.json's
// world_to_export (inverted); InputError naming the file when that is missing or the groom was
// posed (a pose moves strands off the scene's body), saying what to compare instead.
struct CommonFrame {
  FileFrame frame = FileFrame::scene;
  std::vector<glm::dmat4> to_common;  // one per file, in order
  std::vector<bool> moved;            // the file was brought back from the export frame
};
CommonFrame common_frame(const std::vector<std::filesystem::path>& files, bool scene_required = false);

// Applies a 4x4 map to xyz triples in place.
void transform_points(std::vector<float>& xyz, const glm::dmat4& m);

}  // namespace nf::io
