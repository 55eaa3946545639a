// Images: PNG (8 and 16 bit) and JPEG through stb, OpenEXR through OpenEXR; masks from alpha; sizes
// from headers and truncated files found without decoding.
#include <doctest/doctest.h>

#include <stb/stb_image_write.h>

#include <cmath>
#include <filesystem>
#include <cstdint>
#include <fstream>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/io/image.hpp"
#include "engine/io/image_size.hpp"
#include "engine/io/jpeg_exif.hpp"
#include "engine/io/mask_agreement.hpp"

using namespace nf;
using namespace nf::io;
namespace fs = std::filesystem;

TEST_CASE("8-bit PNG round-trips exactly and gives its alpha as the mask") {
  Image img{4, 3, 4, {}};
  for (std::uint32_t i = 0; i < 4 * 3; ++i) img.pixels.insert(img.pixels.end(), {i / 255.f, 0.5f, 1.f, i % 2 ? 1.f : 0.f});
  const fs::path path = fs::temp_directory_path() / "nf_test_image.png";
  write_png(path, img);
  const Image r = read_image(path);
  CHECK(r.width == 4);
  CHECK(r.height == 3);
  CHECK(r.channels == 4);
  for (std::size_t i = 0; i < img.pixels.size(); ++i) CHECK(r.pixels[i] == doctest::Approx(std::round(img.pixels[i] * 255) / 255));
  const auto mask = mask_of(r);
  CHECK(mask[0] == 0);
  CHECK(mask[1] == 1);
  CHECK(image_size(path) == std::pair<std::uint32_t, std::uint32_t>{4, 3});
  fs::remove(path);
}

TEST_CASE("16-bit PNG keeps its precision") {
  const Image r = read_image(fs::path(NF_TEST_DATA) / "gray16.png");
  REQUIRE(r.channels == 1);
  CHECK(r.at(1, 0, 0) == doctest::Approx(1000 / 65535.0).epsilon(1e-6));
  CHECK(r.at(2, 1, 0) == doctest::Approx(7 / 65535.0).epsilon(1e-6));
  CHECK(r.at(2, 0, 0) == 1.f);
}

TEST_CASE("JPEG decodes to the size and roughly the colour written") {
  std::vector<unsigned char> rgb(16 * 8 * 3, 200);
  const fs::path path = fs::temp_directory_path() / "nf_test_image.jpg";
  REQUIRE(stbi_write_jpg(path.c_str(), 16, 8, 3, rgb.data(), 95));
  const Image r = read_image(path);
  CHECK(r.width == 16);
  CHECK(r.height == 8);
  CHECK(r.at(5, 5, 1) == doctest::Approx(200 / 255.0).epsilon(0.02));
  fs::remove(path);
}

TEST_CASE("a camera's EXIF in a JPEG: the pixels decode as before, and the tags are where the TIFF layout puts them") {
  Image img{16, 8, 3, {}};
  for (std::uint32_t i = 0; i < 16 * 8; ++i) img.pixels.insert(img.pixels.end(), {(i % 16) / 15.f, (i / 16) / 7.f, 0.5f});
  const std::string plain = encode_jpeg(img, 92);
  const std::string tagged = with_exif(plain, {"nf_gpu", "synth camera", 24.5, 36.0});
  // SOI, then APP1 "Exif\0\0", then a little-endian TIFF header pointing at IFD0.
  REQUIRE(tagged.size() > plain.size());
  CHECK(std::uint8_t(tagged[2]) == 0xff);
  CHECK(std::uint8_t(tagged[3]) == 0xe1);
  CHECK(std::size_t(std::uint8_t(tagged[4])) * 256 + std::uint8_t(tagged[5]) + 2 == tagged.size() - plain.size());
  CHECK(tagged.compare(6, 6, std::string("Exif\0\0", 6)) == 0);
  const std::string tiff = tagged.substr(12, tagged.size() - plain.size() - 10);
  const auto u16 = [&](std::size_t at) { return unsigned(std::uint8_t(tiff[at])) | unsigned(std::uint8_t(tiff[at + 1])) << 8; };
  const auto u32 = [&](std::size_t at) { return u16(at) | u16(at + 2) << 16; };
  CHECK(tiff.substr(0, 4) == std::string("II*\0", 4));
  const std::size_t ifd0 = u32(4);
  REQUIRE(u16(ifd0) == 3);
  CHECK(u16(ifd0 + 2) == 0x010f);  // Make, ASCII, at an offset
  CHECK(tiff.substr(u32(ifd0 + 2 + 8), 7) == std::string("nf_gpu\0", 7));
  CHECK(u16(ifd0 + 2 + 24) == 0x8769);
  const std::size_t exif_ifd = u32(ifd0 + 2 + 24 + 8);
  REQUIRE(u16(exif_ifd) == 2);
  CHECK(u16(exif_ifd + 2) == 0x920a);  // FocalLength, RATIONAL: 2450 / 100
  const std::size_t rational = u32(exif_ifd + 2 + 8);
  CHECK(u32(rational) == 2450);
  CHECK(u32(rational + 4) == 100);
  CHECK(u16(exif_ifd + 14) == 0xa405);  // FocalLengthIn35mmFilm, SHORT, inline
  CHECK(u16(exif_ifd + 14 + 8) == 36);
  const fs::path a = fs::temp_directory_path() / "nf_test_plain.jpg", b = fs::temp_directory_path() / "nf_test_exif.jpg";
  std::ofstream(a, std::ios::binary) << plain;
  std::ofstream(b, std::ios::binary) << tagged;
  CHECK(read_image(a).pixels == read_image(b).pixels);
  CHECK(image_size(b) == std::pair<std::uint32_t, std::uint32_t>(16, 8));
  CHECK_THROWS_AS(with_exif("not a jpeg", {}), InputError);
  fs::remove(a), fs::remove(b);
}

TEST_CASE("OpenEXR round-trips float values exactly, one channel or four") {
  for (std::uint32_t channels : {1u, 4u}) {
    Image img{5, 2, channels, {}};
    for (std::uint32_t i = 0; i < 5 * 2 * channels; ++i) img.pixels.push_back(-3.5f + 0.37f * float(i) + (i == 3 ? 1e6f : 0.f));
    const fs::path path = fs::temp_directory_path() / "nf_test_image.exr";
    write_exr(path, img);
    const Image r = read_image(path);
    CHECK(r.channels == channels);
    CHECK(r.pixels == img.pixels);
    fs::remove(path);
  }
}

TEST_CASE("broken images are refused with the file named") {
  const fs::path path = fs::temp_directory_path() / "nf_test_broken.png";
  std::ifstream in(fs::path(NF_TEST_DATA) / "gray16.png", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(path, std::ios::binary) << bytes.substr(0, 40);
  CHECK_THROWS_WITH_AS(read_image(path), doctest::Contains("nf_test_broken.png"), InputError);
  std::ofstream(fs::temp_directory_path() / "nf_test_broken.exr") << "not an exr";
  CHECK_THROWS_WITH_AS(read_image(fs::temp_directory_path() / "nf_test_broken.exr"), doctest::Contains("cannot read EXR"),
                       InputError);
  CHECK_THROWS_WITH_AS(read_image(fs::temp_directory_path() / "nf_no_such.png"), doctest::Contains("cannot open"), InputError);
  fs::remove(path);
  fs::remove(fs::temp_directory_path() / "nf_test_broken.exr");
}

TEST_CASE("an image header declaring more pixels than its file holds is refused before decoding") {
  // The fuzzer's finding: 14 bytes of PGM header declaring 3,288,525 x 228 pixels made the decoder
  // allocate 0.75 GB and read_image 3 GB.
  const fs::path path = fs::temp_directory_path() / "nf_test_huge_header.png";
  std::ofstream(path, std::ios::binary) << "P53288525\r228\x86";
  CHECK_THROWS_WITH_AS(read_image(path), doctest::Contains("declares 3288525 x 228 pixels, more than nf_gpu reads"), InputError);
  std::ofstream(path, std::ios::binary) << "P5 8000 8000 255 ";
  CHECK_THROWS_WITH_AS(read_image(path), doctest::Contains("declares 8000 x 8000 pixels in 17 bytes: truncated"), InputError);
  // The same for EXR (the fuzzer's finding: 304 bytes declaring a data window that took seconds to
  // allocate and fill).
  CHECK_THROWS_WITH_AS(read_image(fs::path(NF_TEST_DATA) / "huge_window.exr"), doctest::Contains("bytes: truncated or not an image"), InputError);
  // The campaign's next one (11 s under the sanitizers): a channel list declaring more bytes than
  // it holds, which OpenEXR reads by its structure, so the data window it then finds is not where a
  // walk by declared sizes looks. Now the list must hold what it declares, and the window is taken
  // from OpenEXR's own reading of the header.
  CHECK_THROWS_WITH_AS(read_image(fs::path(NF_TEST_DATA) / "window_after_long_chlist.exr"),
                       doctest::Contains("EXR channel list declares 51 bytes and holds 19: corrupt EXR header"), InputError);
  // An EXR header attribute declaring 2 GB in a 30-byte file (OpenEXR would allocate it first).
  const fs::path exr = fs::temp_directory_path() / "nf_test_huge_attribute.exr";
  std::ofstream(exr, std::ios::binary) << std::string("\x76\x2f\x31\x01\x02\x00\x00\x00", 8) << std::string("channels\0chlist\0", 16)
                                       << std::string("\x00\x00\xff\x7f", 4) << "xx";
  CHECK_THROWS_WITH_AS(read_image(exr), doctest::Contains("attribute 'channels' declares 2147418112 bytes, the file holds 30"), InputError);
  // The same attribute after a small data window (the campaign's next finding: only the attributes
  // before the data window were checked, and OpenEXR cleared megabytes per input).
  std::ofstream(exr, std::ios::binary) << std::string("\x76\x2f\x31\x01\x02\x00\x00\x00", 8) << std::string("dataWindow\0box2i\0", 17)
                                       << std::string("\x10\0\0\0", 4) << std::string(8, '\0') << std::string("\x01\0\0\0\x01\0\0\0", 8)
                                       << std::string("junk\0opaque\0", 12) << std::string("\x00\x00\x00\x01", 4) << "xx";
  CHECK_THROWS_WITH_AS(read_image(exr), doctest::Contains("attribute 'junk' declares 16777216 bytes"), InputError);
  // And in the second header of a multi-part file.
  std::ofstream(exr, std::ios::binary) << std::string("\x76\x2f\x31\x01\x02\x10\x00\x00", 8) << std::string("name\0string\0", 12)
                                       << std::string("\x01\0\0\0", 4) << "a" << std::string(1, '\0') << std::string("name\0string\0", 12)
                                       << std::string("\x00\x00\x00\x01", 4) << "xx";
  CHECK_THROWS_WITH_AS(read_image(exr), doctest::Contains("attribute 'name' declares 16777216 bytes"), InputError);
  // A data window of 300 x 300 halves (180 KB) in about 120 bytes: refused uncompressed, passed on
  // to OpenEXR (which then finds the header incomplete) under DWAA, whose blocks can pack that far.
  const auto small_exr = [&](char compression) {
    std::string chlist = std::string("Y\0", 2) + std::string("\x01\0\0\0", 4) + std::string(4, '\0') + std::string("\x01\0\0\0\x01\0\0\0", 8) + std::string(1, '\0');
    std::ofstream(exr, std::ios::binary) << std::string("\x76\x2f\x31\x01\x02\x00\x00\x00", 8) << std::string("channels\0chlist\0", 16)
                                         << std::string("\x13\0\0\0", 4) << chlist << std::string("compression\0compression\0", 24)
                                         << std::string("\x01\0\0\0", 4) << compression << std::string("dataWindow\0box2i\0", 17)
                                         << std::string("\x10\0\0\0", 4) << std::string(8, '\0') << std::string("\x2b\x01\0\0\x2b\x01\0\0", 8)
                                         << std::string(1, '\0') << std::string(16, '\0');
  };
  small_exr('\0');
  CHECK_THROWS_WITH_AS(read_image(exr), doctest::Contains("declares 300 x 300 pixels of 2.0"), InputError);
  CHECK_THROWS_WITH_AS(read_image(exr), doctest::Contains("hold under its compression (0): truncated or not an EXR"), InputError);
  small_exr('\x08');
  CHECK_THROWS_WITH_AS(read_image(exr), doctest::Contains("cannot read EXR"), InputError);
  fs::remove(exr);
  // A uniform mask compresses far (here 100:1) and is still read.
  std::vector<std::uint8_t> black(std::size_t(2000) * 1500, 0);
  REQUIRE(stbi_write_png(path.c_str(), 2000, 1500, 1, black.data(), 2000));
  CHECK(read_image(path).width == 2000);
  fs::remove(path);
}

TEST_CASE("image_size reads PNG and JPEG headers; require_complete_image finds files cut short") {
  const fs::path png = fs::temp_directory_path() / "nf_test_size.png", jpg = fs::temp_directory_path() / "nf_test_size.jpg";
  std::vector<unsigned char> rgb(40 * 30 * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<unsigned char>(i * 7);
  REQUIRE(stbi_write_png(png.c_str(), 40, 30, 3, rgb.data(), 40 * 3));
  REQUIRE(stbi_write_jpg(jpg.c_str(), 40, 30, 3, rgb.data(), 90));
  const auto slurp = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const auto spit = [](const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; };
  const std::string png_bytes = slurp(png), jpg_bytes = slurp(jpg);
  for (const fs::path& p : {png, jpg}) {
    CAPTURE(p);
    CHECK(image_size(p) == std::pair<std::uint32_t, std::uint32_t>{40, 30});
    CHECK_NOTHROW(require_complete_image(p));
  }
  // Data after a complete image (phones append a video to a JPEG; tools append to PNGs) is accepted.
  spit(jpg, jpg_bytes + std::string("\0\0\0\x18" "ftypmp42") + std::string(3000, 'v'));
  CHECK_NOTHROW(require_complete_image(jpg));
  spit(png, png_bytes + "trailing");
  CHECK_NOTHROW(require_complete_image(png));
  // Cut short: the header still gives the size, the check says "truncated" and names the file.
  spit(png, png_bytes.substr(0, png_bytes.size() - 30));
  CHECK(image_size(png).first == 40);
  CHECK_THROWS_WITH_AS(require_complete_image(png), doctest::Contains("nf_test_size.png: truncated PNG"), InputError);
  spit(jpg, jpg_bytes.substr(0, jpg_bytes.size() - 30));
  CHECK(image_size(jpg).second == 30);
  CHECK_THROWS_WITH_AS(require_complete_image(jpg), doctest::Contains("nf_test_size.jpg: truncated JPEG"), InputError);
  // Cut inside the header, or not an image at all.
  spit(png, png_bytes.substr(0, 20));
  CHECK_THROWS_WITH_AS(image_size(png), doctest::Contains("nf_test_size.png: truncated or corrupt PNG header"), InputError);
  spit(jpg, jpg_bytes.substr(0, 10));
  CHECK_THROWS_WITH_AS(image_size(jpg), doctest::Contains("truncated or corrupt JPEG header"), InputError);
  spit(png, "GIF89a and more");
  CHECK_THROWS_WITH_AS(image_size(png), doctest::Contains("not a PNG or JPEG"), InputError);
  CHECK_THROWS_WITH_AS(require_complete_image(png), doctest::Contains("not a PNG or JPEG"), InputError);
  fs::remove(png);
  fs::remove(jpg);
}

TEST_CASE("a mask's edge follows its own photo's outline, not another photo's") {
  // A bright disc on a dark, slightly noisy background: its own mask's edge sits on the step; a mask
  // shifted by 12 pixels (another photo's) cuts through flat disc and flat background.
  const std::uint32_t w = 96, h = 80;
  std::vector<std::uint8_t> rgb(std::size_t(w) * h * 3), own(std::size_t(w) * h), shifted(std::size_t(w) * h);
  std::uint32_t noise = 12345;
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x) {
      const std::size_t p = std::size_t(y) * w + x;
      const auto inside = [&](double cx) { return std::hypot(double(x) - cx, double(y) - 40.0) < 25.0; };
      noise = noise * 1664525u + 1013904223u;
      for (int k = 0; k < 3; ++k) rgb[3 * p + k] = std::uint8_t((inside(48) ? 200 : 30) + (noise >> 29));
      own[p] = inside(48), shifted[p] = inside(60);
    }
  const double own_contrast = mask_edge_contrast(rgb, own, w, h), shifted_contrast = mask_edge_contrast(rgb, shifted, w, h);
  CHECK(own_contrast > 5.0);
  CHECK(own_contrast > 2.5 * shifted_contrast);
  // Moving the shifted mask back by 12 pixels finds the photo's outline again.
  CHECK(mask_edge_contrast(rgb, shifted, w, h, -12, 0) == doctest::Approx(own_contrast));
  CHECK(mask_edge_peak(rgb, own, w, h) > 2.0);
  CHECK(mask_edge_peak(rgb, shifted, w, h) < 1.3);
  CHECK(std::isnan(mask_edge_contrast(rgb, std::vector<std::uint8_t>(std::size_t(w) * h, 1), w, h)));  // no edge
}
