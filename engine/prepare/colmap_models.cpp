#include "engine/prepare/colmap_models.hpp"

#include <algorithm>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"

namespace nf::prepare {

namespace fs = std::filesystem;

namespace {

template <class T>
T read_value(std::ifstream& in, const fs::path& file) {
  T value{};
  if (!in.read(reinterpret_cast<char*>(&value), sizeof value)) throw InputError(file.string() + ": cut short (a COLMAP model that was not finished?)");
  return value;
}

// images.bin: a count, then per image its id, pose, camera, name (NUL-terminated) and 2D points.
std::vector<std::string> image_names(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  const auto count = read_value<std::uint64_t>(in, file);
  const auto size = fs::file_size(file);
  if (count > size / 64) throw InputError(file.string() + ": claims " + std::to_string(count) + " images, more than its size holds");
  std::vector<std::string> names;
  for (std::uint64_t i = 0; i < count; ++i) {
    in.seekg(4 + 7 * 8 + 4, std::ios::cur);  // id, quaternion and translation, camera id
    std::string name;
    std::getline(in, name, '\0');
    const auto points = read_value<std::uint64_t>(in, file);
    const auto at = std::uint64_t(in.tellg());
    if (!in || points > size || at + points * 24 > size) throw InputError(file.string() + ": cut short (a COLMAP model that was not finished?)");
    in.seekg(std::streamoff(points * 24), std::ios::cur);
    names.push_back(name);
  }
  return names;
}

std::string some_names(const std::vector<std::string>& names) {
  std::vector<std::string> sorted = names;
  std::sort(sorted.begin(), sorted.end());
  std::string text;
  for (std::size_t i = 0; i < std::min<std::size_t>(3, sorted.size()); ++i) text += (i ? ", " : "") + sorted[i];
  return text + (sorted.size() > 3 ? ", ..." : "");
}

}  // namespace

std::vector<ColmapModel> read_colmap_models(const fs::path& sparse) {
  std::vector<ColmapModel> models;
  if (!fs::is_directory(sparse)) return models;
  for (const fs::directory_entry& e : fs::directory_iterator(sparse))
    if (fs::exists(e.path() / "images.bin")) models.push_back({e.path(), image_names(e.path() / "images.bin")});
  std::sort(models.begin(), models.end(), [](const ColmapModel& a, const ColmapModel& b) {
    return a.images.size() != b.images.size() ? a.images.size() > b.images.size() : a.folder < b.folder;
  });
  return models;
}

const ColmapModel& choose_colmap_model(const std::vector<ColmapModel>& models, std::size_t min_photos, const fs::path& log) {
  if (models.empty() || models.front().images.empty())
    throw InputError("prepare: COLMAP placed no cameras (see " + log.string() +
                     "): the photos share too few features; take more photos with more overlap, of a textured scene");
  const ColmapModel& largest = models.front();
  if (models.size() > 1) {
    const ColmapModel& second = models[1];
    if (second.images.size() >= min_photos && 3 * second.images.size() >= largest.images.size()) {
      std::string groups;
      for (const ColmapModel& m : models)
        groups += "\n  " + std::to_string(m.images.size()) + " photos (" + some_names(m.images) + "), model " + m.folder.string();
      throw InputError("prepare: COLMAP split the photos into " + std::to_string(models.size()) + " groups that share no features:" + groups +
                       "\nPhotos of two animals (or two sessions) belong in two folders, one prepare each. For one animal, add photos "
                       "that bridge the groups (overlapping views, the same light), or keep one group: pass its model with --colmap, the photos with --images (a video's frames are in colmap/frames beside the models) "
                       "and a new --out.");
    }
    log::warn("prepare: COLMAP found ", models.size(), " groups of photos; the largest (", largest.images.size(), " photos) is kept");
  }
  return largest;
}

}  // namespace nf::prepare
