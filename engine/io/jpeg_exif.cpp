#include "engine/io/jpeg_exif.hpp"

#include <cmath>
#include <cstdint>
#include <vector>

#include "engine/core/error.hpp"

namespace nf::io {

namespace {

// A little-endian TIFF structure (the body of an Exif segment): IFDs of 12-byte entries whose
// values longer than 4 bytes live after the IFD, at offsets from the TIFF header.
class Tiff {
 public:
  void u16(std::uint16_t v) { bytes_.push_back(char(v & 0xff)), bytes_.push_back(char(v >> 8)); }
  void u32(std::uint32_t v) { u16(std::uint16_t(v & 0xffff)), u16(std::uint16_t(v >> 16)); }
  void put_u32(std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) bytes_[at + std::size_t(i)] = char((v >> (8 * i)) & 0xff);
  }
  std::size_t size() const { return bytes_.size(); }
  void append(const std::string& s) { bytes_.insert(bytes_.end(), s.begin(), s.end()); }
  const std::vector<char>& bytes() const { return bytes_; }

 private:
  std::vector<char> bytes_;
};

struct Entry {
  std::uint16_t tag, type;  // type 2 ASCII, 3 SHORT, 4 LONG, 5 RATIONAL
  std::uint32_t count;
  std::string data;         // the value's bytes (little endian)
};

std::string le32(std::uint32_t v) {
  std::string s(4, '\0');
  for (int i = 0; i < 4; ++i) s[std::size_t(i)] = char((v >> (8 * i)) & 0xff);
  return s;
}

// An IFD at the current end of `t`, its long values right after it; returns the offset of its
// "next IFD" field. `pointer_entry` (when set) is patched later to point to another IFD.
std::size_t write_ifd(Tiff& t, const std::vector<Entry>& entries) {
  const std::size_t start = t.size();
  std::size_t data_at = start + 2 + 12 * entries.size() + 4;
  std::string data;
  t.u16(std::uint16_t(entries.size()));
  for (const Entry& e : entries) {
    t.u16(e.tag), t.u16(e.type), t.u32(e.count);
    std::string value = e.data;
    if (value.size() <= 4) {
      value.resize(4, '\0');
      t.append(value);
    } else {
      t.u32(std::uint32_t(data_at + data.size()));
      data += value;
      if (data.size() % 2) data += '\0';  // values start on word boundaries
    }
  }
  const std::size_t next = t.size();
  t.u32(0);
  t.append(data);
  return next;
}

}  // namespace

std::string with_exif(const std::string& jpeg, const CameraExif& exif) {
  if (jpeg.size() < 4 || std::uint8_t(jpeg[0]) != 0xff || std::uint8_t(jpeg[1]) != 0xd8) throw InputError("with_exif: the bytes are not a JPEG");
  const auto ascii = [](const std::string& s) { return Entry{0, 2, std::uint32_t(s.size() + 1), s + '\0'}; };
  Entry make = ascii(exif.make), model = ascii(exif.model);
  make.tag = 0x010f, model.tag = 0x0110;
  const std::uint32_t hundredths = std::uint32_t(std::lround(exif.focal_length_mm * 100));
  const std::uint16_t film = std::uint16_t(std::lround(std::min(exif.focal_length_35mm, 65535.0)));

  Tiff t;
  t.append("II");
  t.u16(42);
  t.u32(8);
  // IFD0: maker, model and the pointer to the Exif IFD (patched once that IFD's offset is known).
  write_ifd(t, {make, model, Entry{0x8769, 4, 1, le32(0)}});
  const std::size_t pointer_value = 8 + 2 + 2 * 12 + 8;  // the third entry's value field
  const std::size_t exif_ifd = t.size();
  t.put_u32(pointer_value, std::uint32_t(exif_ifd));
  write_ifd(t, {Entry{0x920a, 5, 1, le32(hundredths) + le32(100)}, Entry{0xa405, 3, 1, std::string{char(film & 0xff), char(film >> 8)}}});

  std::string segment = "Exif";
  segment += '\0', segment += '\0';
  segment.append(t.bytes().begin(), t.bytes().end());
  const std::size_t length = segment.size() + 2;
  if (length > 0xffff) throw InputError("with_exif: the Exif segment is too long");
  std::string out = jpeg.substr(0, 2);
  out += char(0xff), out += char(0xe1), out += char(length >> 8), out += char(length & 0xff);
  out += segment;
  out += jpeg.substr(2);
  return out;
}

}  // namespace nf::io
