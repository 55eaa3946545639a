#include "engine/prepare/video_frames.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/imgproc.hpp>

#include "engine/core/error.hpp"
#include "engine/core/log.hpp"
#include "engine/io/image.hpp"
#include "engine/prepare/external_tool.hpp"

namespace nf::prepare {

namespace fs = std::filesystem;

namespace {

constexpr const char* kInstallHint =
    "prepare --video needs ffmpeg to read the video and none is on PATH: install it (Debian: apt-get install ffmpeg), set NF_FFMPEG and "
    "NF_FFPROBE to its binaries, or extract the frames yourself and pass them with --images";

struct VideoInfo {
  double duration_s = 0;
  double frame_rate = 0;
  std::uint64_t frame_count = 0;  // estimated from the length and rate when the container has no count
  double rotation_deg = 0;
  std::uint32_t width = 0, height = 0;
};

double number_in(const json& object, const char* key) {
  if (!object.contains(key)) return 0;
  const json& v = object[key];
  if (v.is_number()) return v.get<double>();
  if (!v.is_string()) return 0;
  const std::string s = v.get<std::string>();
  if (const std::size_t slash = s.find('/'); slash != std::string::npos) {  // "30000/1001"
    const double den = std::atof(s.c_str() + slash + 1);
    return den > 0 ? std::atof(s.c_str()) / den : 0;
  }
  return std::atof(s.c_str());
}

VideoInfo probe(const fs::path& video, const fs::path& scratch, const fs::path& log) {
  const fs::path out = scratch / "ffprobe.json";
  const std::string ffprobe = find_tool("ffprobe", "NF_FFPROBE", kInstallHint);
  try {
    run_tool(ffprobe, "ffprobe " + video.filename().string(),
             {"-v", "error", "-select_streams", "v:0", "-show_entries",
              "stream=width,height,nb_frames,avg_frame_rate,r_frame_rate,duration:stream_side_data=rotation:format=duration", "-of", "json", video.string()},
             log, out);
  } catch (const InputError& e) {
    throw InputError("prepare: ffmpeg cannot read " + video.string() + " as a video (not a video, or a damaged one; play it to check, or "
                     "extract its frames with another tool and pass them with --images). " + e.what());
  }
  std::ifstream in(out);
  const json probe = json::parse(in, nullptr, false);
  fs::remove(out);
  if (!probe.is_object() || !probe.contains("streams") || !probe["streams"].is_array() || probe["streams"].empty())
    throw InputError("prepare: " + video.string() + " holds no video stream ffmpeg can read");
  const json& stream = probe["streams"][0];
  VideoInfo info;
  // ffprobe's numbers come from the file: bounded before they become counts.
  const auto count = [](double v) { return std::isfinite(v) && v > 0 ? std::min(v, 1e12) : 0.0; };
  info.width = std::uint32_t(std::min(count(number_in(stream, "width")), 1e9)), info.height = std::uint32_t(std::min(count(number_in(stream, "height")), 1e9));
  info.duration_s = number_in(stream, "duration");
  if (!(info.duration_s > 0) && probe.contains("format")) info.duration_s = number_in(probe["format"], "duration");
  info.duration_s = count(info.duration_s);
  info.frame_rate = count(number_in(stream, "avg_frame_rate"));
  if (info.frame_rate == 0) info.frame_rate = count(number_in(stream, "r_frame_rate"));
  info.frame_count = std::uint64_t(count(number_in(stream, "nb_frames")));
  if (info.frame_count == 0) info.frame_count = std::uint64_t(count(std::floor(info.duration_s * info.frame_rate)));
  if (stream.contains("side_data_list") && stream["side_data_list"].is_array())
    for (const json& side : stream["side_data_list"])
      if (side.is_object() && side.contains("rotation")) info.rotation_deg = number_in(side, "rotation");
  if (!(info.duration_s > 0) || info.frame_count == 0)
    throw InputError("prepare: " + video.string() + ": ffprobe finds no length or no frames in its video stream (a damaged or unfinished file?)");
  return info;
}

}  // namespace

void video_tools() {
  find_tool("ffprobe", "NF_FFPROBE", kInstallHint);
  find_tool("ffmpeg", "NF_FFMPEG", kInstallHint);
}

double frame_sharpness(const std::vector<float>& grey, std::uint32_t width, std::uint32_t height) {
  cv::Mat image(int(height), int(width), CV_32F, const_cast<float*>(grey.data()));
  const double shrink = std::min(1.0, 720.0 / double(std::max(width, height)));
  cv::Mat small;
  if (shrink < 1) cv::resize(image, small, cv::Size(), shrink, shrink, cv::INTER_AREA);
  else small = image;
  cv::Mat laplacian;
  cv::Laplacian(small, laplacian, CV_32F);
  cv::Scalar mean, deviation;
  cv::meanStdDev(laplacian, mean, deviation);
  return deviation[0] * deviation[0];
}

json extract_video_frames(const VideoFrameOptions& o) {
  if (!fs::is_regular_file(o.video)) throw InputError("prepare: --video " + o.video.string() + " is not a file");
  if (o.frames == 0 || o.candidates_per_frame == 0) throw UsageError("prepare: --frames must be at least 1");
  fs::create_directories(o.out);
  const fs::path candidates = o.out / "candidates";
  fs::create_directories(candidates);
  const VideoInfo info = probe(o.video, o.out, o.log);
  if (info.frame_count < o.frames)
    throw InputError("prepare: " + o.video.string() + " has " + std::to_string(info.frame_count) + " frames and " + std::to_string(o.frames) +
                     " were asked for (--frames): ask for fewer, or film a longer, slower circle");
  // Evenly spaced candidates over the whole length; every frame when the video has few.
  const std::uint64_t wanted = std::min<std::uint64_t>(info.frame_count, std::uint64_t(o.frames) * o.candidates_per_frame);
  const double rate = double(wanted) / info.duration_s;
  char filter[64];
  std::snprintf(filter, sizeof filter, "fps=%.6f", rate);
  const double seconds = run_tool(find_tool("ffmpeg", "NF_FFMPEG", kInstallHint), "ffmpeg " + o.video.filename().string(),
                                  {"-nostdin", "-v", "error", "-i", o.video.string(), "-map", "0:v:0", "-vf", filter, "-q:v", "2", (candidates / "%06d.jpg").string()}, o.log);
  std::vector<fs::path> files;
  for (const fs::directory_entry& e : fs::directory_iterator(candidates)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  if (files.size() < o.frames)
    throw InputError("prepare: ffmpeg decoded " + std::to_string(files.size()) + " frames of " + o.video.string() + ", fewer than the " +
                     std::to_string(o.frames) + " asked for (see " + o.log.string() + ")");

  std::vector<double> sharpness(files.size());
  for (std::size_t i = 0; i < files.size(); ++i) {
    const io::Image frame = io::read_image(files[i]);
    std::vector<float> grey(std::size_t(frame.width) * frame.height);
    for (std::size_t p = 0; p < grey.size(); ++p) {
      float sum = 0;
      for (std::uint32_t c = 0; c < std::min(frame.channels, 3u); ++c) sum += frame.pixels[p * frame.channels + c];
      grey[p] = sum / float(std::min(frame.channels, 3u));
    }
    sharpness[i] = frame_sharpness(grey, frame.width, frame.height);
  }
  std::vector<double> sorted = sharpness;
  std::nth_element(sorted.begin(), sorted.begin() + long(sorted.size() / 2), sorted.end());
  const double median = sorted[sorted.size() / 2];

  json kept = json::array();
  std::vector<std::string> soft;
  for (std::uint32_t k = 0; k < o.frames; ++k) {
    const std::size_t begin = k * files.size() / o.frames, end = (k + 1) * files.size() / o.frames;
    const std::size_t best = std::size_t(std::max_element(sharpness.begin() + long(begin), sharpness.begin() + long(end)) - sharpness.begin());
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04u.jpg", k + 1);
    fs::rename(files[best], o.out / name);
    // The fps filter's n-th frame stands for time n / rate.
    kept.push_back({{"file", name}, {"time_s", double(best) / rate}, {"sharpness", sharpness[best]}});
    if (sharpness[best] < 0.35 * median) soft.push_back(name);
  }
  fs::remove_all(candidates);
  if (!soft.empty())
    log::warn("prepare: ", soft.size(), " kept frame(s) are blurred (", soft.front(), soft.size() > 1 ? ", ..." : "",
              "): no sharp frame in that stretch of the video; move the camera more slowly there");
  return {{"video", fs::absolute(o.video).string()}, {"duration_s", info.duration_s}, {"frame_rate", info.frame_rate},
          {"frame_count", info.frame_count}, {"rotation_deg", info.rotation_deg}, {"width", info.width}, {"height", info.height},
          {"candidates", files.size()}, {"sharpness_median", median}, {"decode_seconds", seconds}, {"frames", kept}, {"blurred_frames", soft}};
}

}  // namespace nf::prepare
