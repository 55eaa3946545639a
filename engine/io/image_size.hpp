#pragma once
// Cheap checks of PNG and JPEG files that do not decode the pixels: the size from the header (camera
// readers need it; the stages decode images when they use them), and whether the file is complete.
#include <cstdint>
#include <filesystem>
#include <utility>

namespace nf::io {

// (width, height); throws InputError naming the file when it is not a PNG or JPEG, or its header is
// truncated or corrupt.
std::pair<std::uint32_t, std::uint32_t> image_size(const std::filesystem::path& path);

// The channel count a decoder gives (PNG: 2 or 4 with an alpha channel or a transparent colour).
std::uint32_t image_channels(const std::filesystem::path& path);

// Throws InputError naming the file and saying "truncated" when a PNG ends before its IEND chunk or
// a JPEG before its end-of-image marker (an interrupted copy or download). Reads the last bytes only,
// unless data follows the image's end (phones' motion photos append a video to the JPEG).
void require_complete_image(const std::filesystem::path& path);

}  // namespace nf::io
