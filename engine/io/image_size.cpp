#include "engine/io/image_size.hpp"

#include <cstring>
#include <fstream>
#include <vector>

#include "engine/core/error.hpp"

namespace nf::io {
namespace {

std::uint32_t big_endian(const unsigned char* p, int bytes) {
  std::uint32_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

std::pair<std::uint32_t, std::uint32_t> image_size(const std::filesystem::path& path) {
  const std::string where = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(where + ": cannot open image");
  std::vector<unsigned char> head(1 << 16);
  in.read(reinterpret_cast<char*>(head.data()), std::streamsize(head.size()));
  const std::size_t n = std::size_t(in.gcount());
  static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (n >= 24 && std::memcmp(head.data(), png, 8) == 0 && std::memcmp(&head[12], "IHDR", 4) == 0)
    return {big_endian(&head[16], 4), big_endian(&head[20], 4)};
  if (n >= 4 && head[0] == 0xff && head[1] == 0xd8) {  // JPEG: walk the markers to a start-of-frame
    std::size_t p = 2;
    while (p + 9 < n) {
      if (head[p] != 0xff) break;
      const unsigned marker = head[p + 1];
      const std::size_t length = big_endian(&head[p + 2], 2);
      const bool sof = marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc;
      if (sof) return {big_endian(&head[p + 7], 2), big_endian(&head[p + 5], 2)};
      p += 2 + length;
    }
    throw InputError(where + ": JPEG without a frame header in its first 64 KiB");
  }
  throw InputError(where + ": not a PNG or JPEG image");
}

}  // namespace nf::io
