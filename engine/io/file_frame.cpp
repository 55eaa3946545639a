#include "engine/io/file_frame.hpp"

#include <algorithm>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/io/json_fields.hpp"

namespace nf::io {
namespace fs = std::filesystem;

std::string_view frame_marker(FileFrame frame) {
  switch (frame) {
    case FileFrame::scene: return "nf_gpu frame: scene";
    case FileFrame::exported: return "nf_gpu frame: export";
    default: return "";
  }
}

std::string frame_words(FileFrame frame) {
  switch (frame) {
    case FileFrame::scene: return "the scene's frame";
    case FileFrame::exported: return "the export frame (metres, +y up, the animal facing +z)";
    default: return "no stated frame";
  }
}

FileFrame declared_frame(const fs::path& file) {
  // The marker sits in the header of every format nf_gpu writes; a GLB's JSON lists its accessors
  // before the asset, a few kilobytes.
  constexpr std::size_t kHead = 1 << 16;
  std::ifstream in(file, std::ios::binary);
  if (!in) return FileFrame::unknown;
  std::string head(kHead, '\0');
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(std::size_t(in.gcount()));
  for (const FileFrame f : {FileFrame::exported, FileFrame::scene})
    if (head.find(frame_marker(f)) != std::string::npos) return f;
  // A file exported before files stated their frame: the export.json beside it lists it.
  const fs::path record = fs::absolute(file).parent_path() / "export.json";
  if (fs::exists(record)) {
    try {
      for (const json& f : read_json_file(record).value("files", json::array()))
        if (f.is_object() && f.value("file", std::string()) == file.filename().string()) return FileFrame::exported;
    } catch (const std::exception&) {  // not an export.json of ours: it says nothing
    }
  }
  return FileFrame::unknown;
}

namespace {

// The map from the export frame back to the scene's, from the export.json beside `file`.
glm::dmat4 export_to_scene(const fs::path& file, const fs::path& other, FileFrame other_frame) {
  const fs::path record = fs::absolute(file).parent_path() / "export.json";
  const std::string advice = "compare files of one frame: WORK/fur/strands.hair or an edit's scene_strands.hair, and WORK/defur/bald.ply, are in the scene's frame";
  if (!fs::exists(record))
    throw InputError(file.string() + " is in " + frame_words(FileFrame::exported) + " and " + other.string() + " in " +
                     frame_words(other_frame) + "; no export.json beside it says how to bring it back: " + advice);
  const json j = read_json_file(record);
  const JsonField root(j, record.string());
  if (j.value("posed", false))
    throw InputError(file.string() + " is a posed groom (" + record.string() + ": posed), which no map brings back over the scene; " + advice);
  const glm::dmat4 to_export = matrix_rows(root.at("frame").at("world_to_export"));
  if (!(std::abs(glm::determinant(to_export)) > 0)) root.at("frame").at("world_to_export").fail("is singular");
  return glm::inverse(to_export);
}

}  // namespace

CommonFrame common_frame(const std::vector<fs::path>& files, bool scene_required) {
  CommonFrame c;
  std::vector<FileFrame> frames;
  for (const fs::path& f : files) frames.push_back(declared_frame(f));
  const bool any_scene = std::count(frames.begin(), frames.end(), FileFrame::scene) > 0;
  const bool any_unknown = std::count(frames.begin(), frames.end(), FileFrame::unknown) > 0;
  const bool any_export = std::count(frames.begin(), frames.end(), FileFrame::exported) > 0;
  c.frame = any_export && !any_scene && !any_unknown && !scene_required ? FileFrame::exported : FileFrame::scene;
  for (std::size_t i = 0; i < files.size(); ++i) {
    c.to_common.emplace_back(1.0);
    c.moved.push_back(false);
    if (frames[i] != FileFrame::exported || c.frame == FileFrame::exported) continue;
    // The file it is compared with: the first in the scene's (or no stated) frame.
    const auto other = std::find_if(frames.begin(), frames.end(), [](FileFrame f) { return f != FileFrame::exported; });
    const bool alone = other == frames.end();  // every file is in the export frame, and the scene's is required
    const fs::path& with = alone ? files[i] : files[std::size_t(other - frames.begin())];
    const FileFrame with_frame = alone ? FileFrame::exported : *other;
    c.to_common.back() = export_to_scene(files[i], with, with_frame);
    c.moved.back() = true;
    log::info(files[i].string(), " is in ", frame_words(FileFrame::exported), "; brought back into the scene's frame",
              alone ? std::string() : " of " + with.string(), " through the export.json beside it",
              with_frame == FileFrame::unknown ? " (that file states no frame: the scene's is assumed)" : "");
  }
  return c;
}

void transform_points(std::vector<float>& xyz, const glm::dmat4& m) {
  if (m == glm::dmat4(1.0)) return;
  for (std::size_t p = 0; p + 2 < xyz.size(); p += 3) {
    const glm::dvec4 q = m * glm::dvec4(xyz[p], xyz[p + 1], xyz[p + 2], 1.0);
    xyz[p] = float(q.x), xyz[p + 1] = float(q.y), xyz[p + 2] = float(q.z);
  }
}

}  // namespace nf::io
