// The header scan is stb_image's (stbi_info_from_file; Debian's libstb ships it compiled, so no
// STB_IMAGE_IMPLEMENTATION here). stb reads any format it knows, so the PNG / JPEG signature is
// checked first: the camera readers take those two only.
#include "engine/io/image_size.hpp"

#include <stb/stb_image.h>

#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/io/binary_io.hpp"

namespace nf::io {
namespace {

using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

constexpr unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
constexpr unsigned char kPngEnd[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xae, 0x42, 0x60, 0x82};  // IEND chunk, CRC

enum class Kind { Png, Jpeg };

File open_image(const std::filesystem::path& path) {
  File file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw InputError(path.string() + ": cannot open image");
  return file;
}

Kind kind_of(std::FILE* file, const std::string& where) {
  unsigned char head[8] = {};
  const std::size_t n = std::fread(head, 1, sizeof head, file);
  std::rewind(file);
  if (n == 8 && std::memcmp(head, kPngSignature, 8) == 0) return Kind::Png;
  if (n >= 4 && head[0] == 0xff && head[1] == 0xd8) return Kind::Jpeg;
  throw InputError(where + ": not a PNG or JPEG image");
}

// Up to `n` bytes at the end of the file.
std::vector<unsigned char> tail(std::FILE* file, std::size_t n) {
  std::fseek(file, 0, SEEK_END);
  const long size = std::ftell(file);
  const long start = size > long(n) ? size - long(n) : 0;
  std::fseek(file, start, SEEK_SET);
  std::vector<unsigned char> bytes(std::size_t(size - start));
  bytes.resize(std::fread(bytes.data(), 1, bytes.size(), file));
  return bytes;
}

std::uint32_t big_endian(const unsigned char* p) {
  return std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 | std::uint32_t(p[2]) << 8 | p[3];
}

// The chunks from the signature on reach IEND (data after it is tolerated).
bool png_reaches_end(const std::vector<char>& file) {
  const auto* b = reinterpret_cast<const unsigned char*>(file.data());
  for (std::size_t p = 8; p + 12 <= file.size();) {
    if (std::memcmp(b + p + 4, "IEND", 4) == 0) return true;
    const std::uint64_t length = big_endian(b + p);
    if (length > file.size() - p - 12) return false;
    p += 12 + std::size_t(length);
  }
  return false;
}

// An EOI marker follows the first scan: its entropy-coded data holds no FF D9 (a data byte FF is
// always stuffed as FF 00), so the first FF D9 after the scan header ends the image. The segments
// before it are skipped by their lengths, since an EXIF thumbnail holds an FF D9 of its own.
bool jpeg_reaches_end(const std::vector<char>& file) {
  const auto* b = reinterpret_cast<const unsigned char*>(file.data());
  const std::size_t n = file.size();
  for (std::size_t p = 2; p + 4 <= n;) {
    if (b[p] != 0xff) return false;
    const unsigned marker = b[p + 1];
    if (marker == 0xff) ++p;  // fill byte
    else if (marker == 0xd9) return true;
    else if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd7)) p += 2;  // markers without a length
    else if (marker != 0xda) p += 2 + (std::size_t(b[p + 2]) << 8 | b[p + 3]);
    else {
      for (std::size_t q = p + 2; q + 1 < n; ++q)
        if (b[q] == 0xff && b[q + 1] == 0xd9) return true;
      return false;
    }
  }
  return false;
}

}  // namespace

std::pair<std::uint32_t, std::uint32_t> image_size(const std::filesystem::path& path) {
  const std::string where = path.string();
  const File file = open_image(path);
  const Kind kind = kind_of(file.get(), where);
  int w = 0, h = 0, channels = 0;
  if (!stbi_info_from_file(file.get(), &w, &h, &channels)) {
    const char* reason = stbi_failure_reason();
    throw InputError(where + ": truncated or corrupt " + (kind == Kind::Png ? "PNG" : "JPEG") + " header (" +
                     (reason ? reason : "unreadable") + ")");
  }
  return {std::uint32_t(w), std::uint32_t(h)};
}

std::uint32_t image_channels(const std::filesystem::path& path) {
  const File file = open_image(path);
  const Kind kind = kind_of(file.get(), path.string());
  int w = 0, h = 0, channels = 0;
  if (!stbi_info_from_file(file.get(), &w, &h, &channels))
    throw InputError(path.string() + ": truncated or corrupt " + (kind == Kind::Png ? "PNG" : "JPEG") + " header");
  return std::uint32_t(channels);
}

void require_complete_image(const std::filesystem::path& path) {
  const std::string where = path.string();
  const File file = open_image(path);
  const Kind kind = kind_of(file.get(), where);
  // The common case from the last bytes: a PNG ends with its IEND chunk, a JPEG with FF D9 (some
  // writers pad after it with NULs or a line break).
  std::vector<unsigned char> end = tail(file.get(), 64);
  if (kind == Kind::Png && end.size() >= 12 && std::memcmp(end.data() + end.size() - 12, kPngEnd, 12) == 0) return;
  if (kind == Kind::Jpeg) {
    while (!end.empty() && (end.back() == 0 || end.back() == '\n' || end.back() == '\r' || end.back() == ' ')) end.pop_back();
    if (end.size() >= 2 && end[end.size() - 2] == 0xff && end.back() == 0xd9) return;
  }
  // Otherwise walk the file's structure: data may follow a complete image.
  const std::vector<char> bytes = read_file_bytes(path);
  if (kind == Kind::Png ? png_reaches_end(bytes) : jpeg_reaches_end(bytes)) return;
  throw InputError(where + (kind == Kind::Png ? ": truncated PNG: the file ends before its IEND chunk"
                                              : ": truncated JPEG: the file ends before its end-of-image marker") +
                   " (an interrupted copy or download?)");
}

}  // namespace nf::io
