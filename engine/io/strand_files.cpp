#include "engine/io/strand_files.hpp"

#include "engine/core/error.hpp"

namespace nf::io {

void write_strands(const std::filesystem::path& path, const StrandSet& strands) {
  const std::string ext = path.extension().string();
  if (ext == ".hair") return write_hair(path, strands);
  if (ext == ".ply") return write_strands_ply(path, strands);
  if (ext == ".obj") return write_strands_obj(path, strands);
  if (ext == ".usda") return write_strands_usda(path, strands);
  throw InputError(path.string() + ": unknown strand format '" + ext + "' (.hair, .ply, .obj, .usda)");
}

StrandSet read_strands(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".hair") return read_hair(path);
  if (ext == ".ply") return read_strands_ply(path);
  if (ext == ".obj") return read_strands_obj(path);
  if (ext == ".usda") return read_strands_usda(path);
  throw InputError(path.string() + ": unknown strand format '" + ext + "' (.hair, .ply, .obj, .usda)");
}

}  // namespace nf::io
