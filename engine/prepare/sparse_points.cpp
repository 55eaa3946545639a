#include "engine/prepare/sparse_points.hpp"

#include <fstream>
#include <sstream>
#include <unordered_map>

#include "engine/core/error.hpp"

namespace nf::prepare {

namespace fs = std::filesystem;

SparsePoints read_sparse_points(const fs::path& folder) {
  SparsePoints r;
  std::unordered_map<long long, std::size_t> index;
  const fs::path points_file = folder / "points3D.txt", images_file = folder / "images.txt";
  std::ifstream points(points_file), images(images_file);
  if (!points) throw InputError(points_file.string() + ": cannot open");
  if (!images) throw InputError(images_file.string() + ": cannot open");
  std::size_t number = 0;
  for (std::string line; std::getline(points, line);) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    long long id;
    double x, y, z, red, green, blue, error;
    if (!(words >> id >> x >> y >> z >> red >> green >> blue >> error))
      throw InputError(points_file.string() + ":" + std::to_string(number) + ": not a point line");
    index[id] = r.positions.size();
    r.positions.emplace_back(x, y, z);
    r.errors.push_back(error);
  }
  // images.txt: a pose line (ID, QW..TZ, CAMERA_ID, NAME), then its keypoints (X, Y, POINT3D_ID)*.
  std::string name;
  bool pose_line = true;
  number = 0;
  for (std::string line; std::getline(images, line);) {
    ++number;
    if (!line.empty() && line[0] == '#') continue;
    std::istringstream words(line);
    if (pose_line) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      std::string skip;
      for (int k = 0; k < 9; ++k) words >> skip;
      if (!(words >> name)) throw InputError(images_file.string() + ":" + std::to_string(number) + ": not an image line");
      pose_line = false;
      continue;
    }
    pose_line = true;
    std::vector<Observation>& seen = r.observed[name];
    double x, y;
    long long id;
    while (words >> x >> y >> id)
      if (id >= 0)
        if (const auto it = index.find(id); it != index.end()) seen.push_back({{x, y}, it->second});
  }
  return r;
}

}  // namespace nf::prepare
