#pragma once
// Photos from a video (ffmpeg and ffprobe, Debian's `ffmpeg`, as subprocesses): several candidate
// frames per wanted frame, spread evenly over the video and decoded upright (ffmpeg applies the
// rotation a phone records), then in each of `frames` equal stretches of time the sharpest candidate
// (variance of the Laplacian: motion blur and defocus lower it) is kept. The frames are named in
// their order, which COLMAP's sequential matching relies on.
#include <cstdint>
#include <filesystem>

#include "engine/core/json.hpp"

namespace nf::prepare {

struct VideoFrameOptions {
  std::filesystem::path video;
  std::filesystem::path out;        // folder for frame_0001.jpg, ... (created)
  std::uint32_t frames = 60;        // how many to keep
  std::uint32_t candidates_per_frame = 4;
  std::filesystem::path log;        // ffmpeg's output is appended here
};

// ffprobe and ffmpeg (UsageError saying how to install them when missing).
void video_tools();

// Returns the report: the video's length and rotation, and each kept frame's time and sharpness.
// InputError when ffmpeg cannot decode the file or it holds fewer frames than asked for.
json extract_video_frames(const VideoFrameOptions& options);

// The variance of the Laplacian of a grey image (width x height, values 0..1) reduced to at most
// 720 px on its long side, so that the same blur scores alike at any resolution.
double frame_sharpness(const std::vector<float>& grey, std::uint32_t width, std::uint32_t height);

}  // namespace nf::prepare
