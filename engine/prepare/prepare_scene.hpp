#pragma once
// `nf_gpu prepare`: a folder of photos (or a video) of an animal to a scene `reconstruct` reads. COLMAP finds
// the cameras (features, matching, mapping; the largest model kept, the photos it could not place
// named), the photos and their masks are undistorted to pinhole cameras, and the scene is written
// as transforms.json with images/ and masks/ beside it, plus prepare.json (each step's time, the
// photos placed, COLMAP's reprojection error) and colmap/ (its log and model).
#include <cstdint>
#include <filesystem>
#include <optional>

#include "engine/core/json.hpp"

namespace nf::prepare {

struct PrepareOptions {
  std::filesystem::path images;        // the photos (PNG or JPEG); or
  std::filesystem::path video;         // a video, from which `video_frames` sharp frames are taken
  std::uint32_t video_frames = 60;
  std::filesystem::path out;           // the scene folder to write (must not exist yet)
  std::filesystem::path masks;         // one mask per photo (white animal), named like it; empty: the photos' alpha
  std::filesystem::path colmap_model;  // an existing COLMAP sparse model of these photos; empty: run COLMAP
  std::optional<double> cm_per_unit;   // the scene's unit, when the user knows it; or
  std::filesystem::path known_distance;  // two points picked in the photos and their distance (known_distance.hpp)
  std::uint32_t max_features = 4096;   // SIFT features per photo (COLMAP's matching time grows with its square)
  // The longer side of the photos' reduced copies the masks and the floor checks work on; the
  // masks are written at the photos' own size (auto_masks.hpp). 0: 1,024 (photo_mats.hpp).
  std::uint32_t working_side = 0;
};

// Returns prepare.json's content. UsageError / InputError say what to do: too few photos, no masks,
// no COLMAP or ffmpeg, a video that cannot be decoded, photos COLMAP could not place or split into
// two groups, an output folder that exists.
json prepare_scene(const PrepareOptions& options);

}  // namespace nf::prepare
