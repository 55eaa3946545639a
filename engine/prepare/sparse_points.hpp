#pragma once
// The sparse points of a COLMAP text model (points3D.txt) and where each photo observed them
// (images.txt's keypoint lines): what the automatic masks seed the animal and the background from.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace nf::prepare {

struct Observation {
  glm::dvec2 pixel;       // x right, y down, as io::Camera::project counts
  std::size_t point = 0;  // index into SparsePoints::positions
};

struct SparsePoints {
  std::vector<glm::dvec3> positions;
  std::vector<double> errors;                                 // mean reprojection error of each point (px)
  std::map<std::string, std::vector<Observation>> observed;   // by photo file name
};

// Throws InputError naming the file and line of a malformed entry.
SparsePoints read_sparse_points(const std::filesystem::path& model_folder);

}  // namespace nf::prepare
