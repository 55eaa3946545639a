#pragma once
// The models COLMAP's mapper wrote: one per group of photos it could connect. One animal photographed
// all round gives one model (plus, at times, a few stray photos in small ones); two models of
// similar size mean two animals, two sessions, or a circle with a gap, and the user must choose.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace nf::prepare {

struct ColmapModel {
  std::filesystem::path folder;
  std::vector<std::string> images;  // the photos it placed, by name
};

// The binary models under `sparse` (sparse/0, sparse/1, ...), largest first. InputError names a
// model file that is cut short.
std::vector<ColmapModel> read_colmap_models(const std::filesystem::path& sparse);

// The model to keep: the largest. InputError saying what to do when there is none, or when a second
// model has at least `min_photos` photos and a third of the largest's: the photos are of two
// things, and keeping either silently would lose the other.
const ColmapModel& choose_colmap_model(const std::vector<ColmapModel>& models, std::size_t min_photos, const std::filesystem::path& log);

}  // namespace nf::prepare
