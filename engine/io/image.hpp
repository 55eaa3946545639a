#pragma once
// Images as the stages use them: width x height pixels of `channels` floats, row-major from the
// top-left. 8- and 16-bit PNG and JPEG are scaled to [0, 1] (stb_image, from Debian's libstb);
// OpenEXR keeps its float values (R, G, B, A, or a single channel such as Z or Y). Writers are
// atomic: PNG (8 bit) and EXR (32-bit float).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace nf::io {

struct Image {
  std::uint32_t width = 0, height = 0, channels = 0;
  std::vector<float> pixels;  // width * height * channels
  float at(std::uint32_t x, std::uint32_t y, std::uint32_t c) const {
    return pixels[(std::size_t(y) * width + x) * channels + c];
  }
};

// The most pixels an image may declare (16384 x 16384): beyond it, and beyond what its bytes can
// hold, read_image refuses before decoding.
inline constexpr std::uint64_t kMaxImagePixels = std::uint64_t(1) << 28;

// Throws InputError naming the file and the reason (missing, truncated, unsupported, too large).
Image read_image(const std::filesystem::path& path);
void write_png(const std::filesystem::path& path, const Image& image);  // 8 bit, values clamped to [0, 1]
// The bytes of a PNG or JPEG file (8 bit, values clamped to [0, 1]; JPEG: 1 or 3 channels).
std::string encode_png(const Image& image);
std::string encode_jpeg(const Image& image, int quality);
void write_exr(const std::filesystem::path& path, const Image& image);  // 32-bit float channels

// A mask from an image: its alpha channel when it has one (2 or 4 channels), else its first
// channel, thresholded at 0.5. 1 = inside.
std::vector<std::uint8_t> mask_of(const Image& image);

// The pixels of [x0, x1) x [y0, y1) (clamped to the image).
Image crop(const Image& image, std::uint32_t x0, std::uint32_t y0, std::uint32_t x1, std::uint32_t y1);
// Shrunk by area averaging so that its longer side is at most `max_side` (unchanged when it fits).
Image downscale_to(const Image& image, std::uint32_t max_side);

}  // namespace nf::io
