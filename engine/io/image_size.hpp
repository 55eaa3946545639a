#pragma once
// Image dimensions from a PNG or JPEG header, without decoding the pixels (camera readers need the
// size; the stages decode images when they use them).
#include <cstdint>
#include <filesystem>
#include <utility>

namespace nf::io {

// (width, height); throws InputError naming the file when it is not a readable PNG or JPEG.
std::pair<std::uint32_t, std::uint32_t> image_size(const std::filesystem::path& path);

}  // namespace nf::io
