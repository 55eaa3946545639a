#include "engine/io/image.hpp"

#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <IexBaseExc.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfVersion.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <optional>
#include <string>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "engine/io/binary_io.hpp"

namespace nf::io {
namespace {

// OpenEXR writes through this so that the file goes out atomically like every other writer.
class OStreamAdapter : public Imf::OStream {
 public:
  explicit OStreamAdapter(std::ostream& out) : Imf::OStream("nf_gpu"), out_(out) {}
  void write(const char c[], int n) override { out_.write(c, n); }
  uint64_t tellp() override { return std::uint64_t(out_.tellp()); }
  void seekp(uint64_t pos) override { out_.seekp(std::streamoff(pos)); }

 private:
  std::ostream& out_;
};

// OpenEXR reads the bytes the checks below looked at, from memory: the file is read once, and a file
// that changes on disk between the checks and the decoding cannot slip past them.
class MemoryIStream : public Imf::IStream {
 public:
  MemoryIStream(const std::filesystem::path& path, const std::vector<char>& bytes) : Imf::IStream(path.c_str()), bytes_(bytes) {}
  bool read(char c[], int n) override {
    if (n < 0 || std::uint64_t(n) > bytes_.size() - at_) throw Iex::InputExc("unexpected end of file");
    std::memcpy(c, bytes_.data() + at_, std::size_t(n));
    at_ += std::uint64_t(n);
    return at_ < bytes_.size();
  }
  uint64_t tellg() override { return at_; }
  void seekg(uint64_t pos) override { at_ = std::min<std::uint64_t>(pos, bytes_.size()); }

 private:
  const std::vector<char>& bytes_;
  std::uint64_t at_ = 0;
};

// A header may declare any size, and decoding allocates it before reading the pixels: refuse what
// no photo is, and what the file cannot hold (deflate packs at most about 1032:1, and a 1-bit PNG 8
// pixels a byte before that; JPEG and EXR's codecs far less).
void check_declared_size(const std::filesystem::path& path, std::uint64_t w, std::uint64_t h, std::uint64_t channels, std::uint64_t file_bytes) {
  const std::uint64_t declared = w * h;
  const std::string size_text = std::to_string(w) + " x " + std::to_string(h);
  if (declared > kMaxImagePixels)
    throw InputError(path.string() + ": declares " + size_text + " pixels, more than nf_gpu reads (" + std::to_string(kMaxImagePixels) + ")");
  if (declared * std::max<std::uint64_t>(channels, 1) > 8800 * file_bytes + 65536)
    throw InputError(path.string() + ": declares " + size_text + " pixels in " + std::to_string(file_bytes) + " bytes: truncated or not an image");
}

// Every attribute's declared size, in every header (a multi-part file has several), checked against
// the file's size before OpenEXR reads the header: OpenEXR allocates an attribute of a type it does
// not know at its declared size (a 30-byte file declared 2 GB).
void check_exr_attribute_sizes(const std::filesystem::path& path, const std::vector<char>& bytes) {
  if (bytes.size() < 8) return;
  const bool multipart = (std::uint8_t(bytes[5]) & 0x10) != 0;  // version flags, bit 12
  std::size_t at = 8;  // magic number and version
  const auto text = [&]() -> std::optional<std::string> {
    const std::size_t end = std::find(bytes.begin() + std::ptrdiff_t(std::min(at, bytes.size())), bytes.end(), '\0') - bytes.begin();
    if (end >= bytes.size()) return std::nullopt;
    std::string t(bytes.data() + at, end - at);
    at = end + 1;
    return t;
  };
  for (std::size_t attributes = 0; at < bytes.size();) {
    const std::optional<std::string> name = text();
    if (!name) return;
    if (name->empty()) {  // the end of a header; a multi-part file ends with an empty header
      if (!multipart || attributes == 0) return;
      attributes = 0;
      continue;
    }
    ++attributes;
    const std::optional<std::string> type = text();
    if (!type || at + 4 > bytes.size()) return;
    std::int32_t size;
    std::memcpy(&size, bytes.data() + at, 4);
    at += 4;
    if (size < 0 || at + std::size_t(size) > bytes.size())
      throw InputError(path.string() + ": EXR header attribute '" + shorten(*name, 40) + "' declares " + std::to_string(size) + " bytes, the file holds " +
                       std::to_string(bytes.size()) + ": truncated or not an EXR");
    if (*type == "chlist") {
      // OpenEXR reads a channel list by its entries (a name, 16 bytes) up to an empty name, not by
      // its declared size: the two must agree, or the attributes OpenEXR reads next are not these.
      std::size_t end = at;
      while (end < bytes.size() && bytes[end] != '\0') {
        end = std::size_t(std::find(bytes.begin() + std::ptrdiff_t(end), bytes.end(), '\0') - bytes.begin()) + 17;
      }
      if (end + 1 != at + std::size_t(size))
        throw InputError(path.string() + ": EXR channel list declares " + std::to_string(size) + " bytes and holds " +
                         (end < bytes.size() ? std::to_string(end + 1 - at) : std::string("more")) + ": corrupt EXR header");
    }
    at += std::size_t(size);
  }
}

// The most pixel bytes one file byte can hold under an EXR compression (Imf::Compression order),
// generously: none 1; RLE 2 bytes a run of at most 128; ZIP, PIZ (Huffman with run codes) and
// PXR24 (zlib after 32 -> 24 bits) below zlib's 1032:1 x 4/3; B44 a 4x4 block of halves in 3 bytes
// at best. 0: no bound beyond check_declared_size's (DWA: a flat 8x8 block is one DC value,
// deflated, so a black image packs far past any of these).
double exr_max_ratio(Imf::Compression compression) {
  static constexpr double kRatio[] = {1, 64, 1400, 1400, 1400, 1400, 11, 11};
  const int c = int(compression);
  return c >= 0 && c < int(std::size(kRatio)) ? kRatio[c] : 0;
}

// The first header, read by OpenEXR itself, checked before OpenEXR opens the file: opening sizes
// its decompression buffers and chunk tables from the data window, so a 200-byte file declaring a
// huge window costs (untouched) gigabytes, and under the sanitizers seconds. The window must fit
// the file under the header's own compression and channels.
void check_exr_header(const std::filesystem::path& path, const std::vector<char>& bytes) {
  const std::uint64_t file_bytes = bytes.size();
  Imf::Header header;
  try {
    MemoryIStream stream(path, bytes);
    char start[8];  // the magic number and the version field, which InputFile reads before the header
    stream.read(start, 8);
    if (!Imf::isImfMagic(start)) throw InputError(path.string() + ": cannot read EXR (not an OpenEXR file)");
    int version = int(std::uint32_t(std::uint8_t(start[4])) | std::uint32_t(std::uint8_t(start[5])) << 8 |
                      std::uint32_t(std::uint8_t(start[6])) << 16 | std::uint32_t(std::uint8_t(start[7])) << 24);
    header.readFrom(stream, version);
  } catch (const nf::Error&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path.string() + ": cannot read EXR (" + e.what() + ")");
  }
  const Imath::Box2i window = header.dataWindow();
  const std::int64_t w = std::int64_t(window.max.x) - window.min.x + 1, h = std::int64_t(window.max.y) - window.min.y + 1;
  if (w <= 0 || h <= 0) throw InputError(path.string() + ": EXR data window of " + std::to_string(w) + " x " + std::to_string(h) + " pixels: empty");
  check_declared_size(path, std::uint64_t(w), std::uint64_t(h), 1, file_bytes);
  if (w > 65536 || h > 65536)
    throw InputError(path.string() + ": EXR data window of " + std::to_string(w) + " x " + std::to_string(h) + " pixels: out of range");
  double bytes_per_pixel = 0;
  for (auto c = header.channels().begin(); c != header.channels().end(); ++c)
    bytes_per_pixel += (c.channel().type == Imf::HALF ? 2.0 : 4.0) / std::max(1.0, double(c.channel().xSampling) * double(c.channel().ySampling));
  const double ratio = exr_max_ratio(header.compression());
  if (ratio > 0 && double(w) * double(h) * bytes_per_pixel > ratio * double(file_bytes) + 65536)
    throw InputError(path.string() + ": declares " + std::to_string(w) + " x " + std::to_string(h) + " pixels of " + std::to_string(bytes_per_pixel) +
                     " bytes, more than " + std::to_string(file_bytes) + " bytes hold under its compression (" +
                     std::to_string(int(header.compression())) + "): truncated or not an EXR");
}

Image read_exr(const std::filesystem::path& path) {
  const std::vector<char> bytes = read_file_bytes(path);  // InputError naming the file when it cannot be read
  const std::uint64_t file_bytes = bytes.size();
  check_exr_attribute_sizes(path, bytes);
  check_exr_header(path, bytes);
  try {
    MemoryIStream stream(path, bytes);
    Imf::InputFile file(stream);
    const Imath::Box2i window = file.header().dataWindow();  // check_exr_header's, from the same bytes
    const long long w = window.max.x - window.min.x + 1, h = window.max.y - window.min.y + 1;
    std::vector<std::string> names;
    for (const char* c : {"R", "G", "B", "A"})
      if (file.header().channels().findChannel(c)) names.emplace_back(c);
    if (names.empty())
      for (auto it = file.header().channels().begin(); it != file.header().channels().end() && names.empty(); ++it)
        names.emplace_back(it.name());  // a single-channel image: Z, Y, depth...
    if (names.empty()) throw InputError(path.string() + ": EXR without channels");
    check_declared_size(path, std::uint64_t(w), std::uint64_t(h), names.size(), file_bytes);
    Image img;
    img.width = std::uint32_t(w), img.height = std::uint32_t(h), img.channels = std::uint32_t(names.size());
    img.pixels.assign(std::size_t(w) * std::size_t(h) * names.size(), 0.f);
    Imf::FrameBuffer fb;
    const std::size_t xstride = sizeof(float) * names.size(), ystride = xstride * std::size_t(w);
    for (std::size_t c = 0; c < names.size(); ++c) {
      char* base = reinterpret_cast<char*>(img.pixels.data() + c) - window.min.x * std::ptrdiff_t(xstride) -
                   window.min.y * std::ptrdiff_t(ystride);
      fb.insert(names[c], Imf::Slice(Imf::FLOAT, base, xstride, ystride));
    }
    file.setFrameBuffer(fb);
    file.readPixels(window.min.y, window.max.y);
    return img;
  } catch (const nf::Error&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path.string() + ": cannot read EXR (" + e.what() + ")");
  }
}

}  // namespace

Image read_image(const std::filesystem::path& path) {
  const std::string ext = to_lower(path.extension().string());
  if (ext == ".exr") return read_exr(path);
  const std::vector<char> bytes = read_file_bytes(path);
  const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
  const int size = int(std::min<std::size_t>(bytes.size(), std::size_t(INT32_MAX)));
  int w = 0, h = 0, c = 0;
  if (!stbi_info_from_memory(data, size, &w, &h, &c))
    throw InputError(path.string() + ": not a readable PNG or JPEG (" + stbi_failure_reason() + ")");
  check_declared_size(path, std::uint64_t(w), std::uint64_t(h), std::uint64_t(std::max(c, 1)), bytes.size());
  Image img;
  if (stbi_is_16_bit_from_memory(data, size)) {
    std::unique_ptr<stbi_us, void (*)(void*)> px(stbi_load_16_from_memory(data, size, &w, &h, &c, 0), stbi_image_free);
    if (!px) throw InputError(path.string() + ": cannot decode (" + stbi_failure_reason() + ")");
    img.pixels.resize(std::size_t(w) * h * c);
    for (std::size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = px.get()[i] / 65535.f;
  } else {
    std::unique_ptr<stbi_uc, void (*)(void*)> px(stbi_load_from_memory(data, size, &w, &h, &c, 0), stbi_image_free);
    if (!px) throw InputError(path.string() + ": cannot decode (" + stbi_failure_reason() + ")");
    img.pixels.resize(std::size_t(w) * h * c);
    for (std::size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = px.get()[i] / 255.f;
  }
  img.width = std::uint32_t(w), img.height = std::uint32_t(h), img.channels = std::uint32_t(c);
  return img;
}

namespace {

std::vector<std::uint8_t> eight_bit(const Image& img, const char* what) {
  if (img.channels < 1 || img.channels > 4 || img.pixels.size() != std::size_t(img.width) * img.height * img.channels)
    throw InternalError(std::string(what) + ": image of " + std::to_string(img.channels) + " channels does not match its size");
  std::vector<std::uint8_t> bytes(img.pixels.size());
  for (std::size_t i = 0; i < bytes.size(); ++i)
    bytes[i] = std::uint8_t(std::lround(std::clamp(std::isfinite(img.pixels[i]) ? img.pixels[i] : 0.f, 0.f, 1.f) * 255.f));
  return bytes;
}

void append_to_string(void* context, void* data, int n) {
  static_cast<std::string*>(context)->append(static_cast<char*>(data), std::size_t(n));
}

}  // namespace

std::string encode_png(const Image& img) {
  const std::vector<std::uint8_t> bytes = eight_bit(img, "encode_png");
  std::string encoded;
  if (!stbi_write_png_to_func(append_to_string, &encoded, int(img.width), int(img.height), int(img.channels), bytes.data(),
                              int(img.width * img.channels)))
    throw InternalError("PNG encoding failed");
  return encoded;
}

std::string encode_jpeg(const Image& img, int quality) {
  const std::vector<std::uint8_t> bytes = eight_bit(img, "encode_jpeg");
  std::string encoded;
  if (!stbi_write_jpg_to_func(append_to_string, &encoded, int(img.width), int(img.height), int(img.channels), bytes.data(),
                              std::clamp(quality, 1, 100)))
    throw InternalError("JPEG encoding failed");
  return encoded;
}

void write_png(const std::filesystem::path& path, const Image& img) { write_file_atomic(path, encode_png(img)); }

void write_exr(const std::filesystem::path& path, const Image& img) {
  if (img.channels < 1 || img.channels > 4 || img.pixels.size() != std::size_t(img.width) * img.height * img.channels)
    throw InternalError("write_exr: image of " + std::to_string(img.channels) + " channels does not match its size");
  static const char* rgba[] = {"R", "G", "B", "A"};
  Imf::Header header(int(img.width), int(img.height));
  for (std::uint32_t c = 0; c < img.channels; ++c)
    header.channels().insert(img.channels == 1 ? "Y" : rgba[c], Imf::Channel(Imf::FLOAT));
  write_file_atomic(path, [&](std::ostream& out) {
    OStreamAdapter stream(out);
    Imf::OutputFile file(stream, header);
    Imf::FrameBuffer fb;
    const std::size_t xstride = sizeof(float) * img.channels, ystride = xstride * img.width;
    for (std::uint32_t c = 0; c < img.channels; ++c)
      fb.insert(img.channels == 1 ? "Y" : rgba[c],
                Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(img.pixels.data() + c)), xstride, ystride));
    file.setFrameBuffer(fb);
    file.writePixels(int(img.height));
  });
}

std::vector<std::uint8_t> mask_of(const Image& img) {
  const std::uint32_t channel = (img.channels == 2 || img.channels == 4) ? img.channels - 1 : 0;
  std::vector<std::uint8_t> mask(std::size_t(img.width) * img.height);
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = img.pixels[i * img.channels + channel] >= 0.5f ? 1 : 0;
  return mask;
}

Image crop(const Image& img, std::uint32_t x0, std::uint32_t y0, std::uint32_t x1, std::uint32_t y1) {
  x1 = std::min(x1, img.width), y1 = std::min(y1, img.height);
  x0 = std::min(x0, x1), y0 = std::min(y0, y1);
  Image out{x1 - x0, y1 - y0, img.channels, {}};
  out.pixels.resize(std::size_t(out.width) * out.height * out.channels);
  for (std::uint32_t y = 0; y < out.height; ++y)
    std::copy_n(img.pixels.begin() + std::ptrdiff_t((std::size_t(y0 + y) * img.width + x0) * img.channels),
                std::size_t(out.width) * img.channels, out.pixels.begin() + std::ptrdiff_t(std::size_t(y) * out.width * out.channels));
  return out;
}

Image downscale_to(const Image& img, std::uint32_t max_side) {
  const std::uint32_t longer = std::max(img.width, img.height);
  if (longer <= max_side || max_side == 0) return img;
  const double f = double(longer) / double(max_side);
  Image out{std::max(1u, std::uint32_t(std::lround(img.width / f))), std::max(1u, std::uint32_t(std::lround(img.height / f))),
            img.channels, {}};
  out.pixels.assign(std::size_t(out.width) * out.height * out.channels, 0.f);
  const double sx = double(img.width) / out.width, sy = double(img.height) / out.height;
  // Each output pixel averages the source pixels its footprint covers, weighted by overlap.
  for (std::uint32_t y = 0; y < out.height; ++y)
    for (std::uint32_t x = 0; x < out.width; ++x) {
      const double ax = x * sx, bx = (x + 1) * sx, ay = y * sy, by = (y + 1) * sy;
      double weight = 0;
      float* o = &out.pixels[(std::size_t(y) * out.width + x) * out.channels];
      for (std::uint32_t v = std::uint32_t(ay); v < std::min<double>(by, img.height); ++v)
        for (std::uint32_t u = std::uint32_t(ax); u < std::min<double>(bx, img.width); ++u) {
          const double w = (std::min<double>(bx, u + 1) - std::max<double>(ax, u)) * (std::min<double>(by, v + 1) - std::max<double>(ay, v));
          if (w <= 0) continue;
          weight += w;
          for (std::uint32_t c = 0; c < img.channels; ++c) o[c] += float(w * img.at(u, v, c));
        }
      for (std::uint32_t c = 0; c < img.channels; ++c) o[c] = weight > 0 ? float(o[c] / weight) : 0.f;
    }
  return out;
}

}  // namespace nf::io
