#pragma once
// A fur view's targets kept for a resumed run. Making a view reads its photo and runs its Gabor
// maps at full resolution (two minutes for 36 views of 2048 px, more for larger photos), while
// reading the result back takes a moment; a requeued or interrupted fur stage reads back the views
// its earlier run finished. The files live in the stage's resume folder, whose key (settings,
// inputs, version) already says they are this run's; each file names its camera, and a file that is
// not whole, not of this scene's camera, larger than its photo or holding values no view has (not
// finite, a zero-sized crop) is made anew, never trusted.
#include <filesystem>
#include <optional>

#include "engine/fur/fur_views.hpp"

namespace nf::fur {

struct StoredFurView {
  FurView view;
  std::optional<io::Camera> native_crop;  // the crop of the view's native targets (fur_patches.hpp), when it had them
};

// Written atomically: a kill leaves the earlier file or none. InputError naming the file when it
// cannot be written.
void write_fur_view(const std::filesystem::path& file, const FurView& view, const io::Camera* native_crop);

// The view, with the scene's camera (its pose, name and files) and the stored crop's intrinsics;
// nullopt (and a warning naming the file) when the file is missing, not whole, of another format
// version, of another camera than the scene's, or holds a crop or values no view has.
std::optional<StoredFurView> read_fur_view(const std::filesystem::path& file, const io::Scene& scene);

}  // namespace nf::fur
