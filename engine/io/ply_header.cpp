#include "engine/io/ply_header.hpp"

#include <algorithm>
#include <charconv>
#include <string_view>

#include "engine/core/error.hpp"

namespace nf::io {
namespace {

constexpr std::size_t kHeaderLimit = 65536;

PlyScalar scalar_type(std::string_view name, const std::string& source) {
  if (name == "char" || name == "int8") return PlyScalar::I8;
  if (name == "uchar" || name == "uint8") return PlyScalar::U8;
  if (name == "short" || name == "int16") return PlyScalar::I16;
  if (name == "ushort" || name == "uint16") return PlyScalar::U16;
  if (name == "int" || name == "int32") return PlyScalar::I32;
  if (name == "uint" || name == "uint32") return PlyScalar::U32;
  if (name == "float" || name == "float32") return PlyScalar::F32;
  if (name == "double" || name == "float64") return PlyScalar::F64;
  throw InputError(source + ": unknown PLY property type '" + std::string(name) + "'");
}

std::vector<std::string_view> words_of(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (true) {
    i = line.find_first_not_of(" \t", i);
    if (i == std::string_view::npos) return words;
    const std::size_t end = std::min(line.find_first_of(" \t", i), line.size());
    words.push_back(line.substr(i, end - i));
    i = end;
  }
}

}  // namespace

const char* ply_type_name(PlyScalar type) {
  switch (type) {
    case PlyScalar::I8: return "char";
    case PlyScalar::U8: return "uchar";
    case PlyScalar::I16: return "short";
    case PlyScalar::U16: return "ushort";
    case PlyScalar::I32: return "int";
    case PlyScalar::U32: return "uint";
    case PlyScalar::F32: return "float";
    case PlyScalar::F64: return "double";
  }
  return "?";
}

PlyHeader parse_ply_header(const std::vector<char>& bytes, const std::string& source) {
  const std::string_view text(bytes.data(), std::min(bytes.size(), kHeaderLimit));
  PlyHeader header;
  bool format_seen = false;
  for (std::size_t start = 0, line_number = 0;; ++line_number) {
    const std::size_t newline = text.find('\n', start);
    std::string_view line = text.substr(start, newline == std::string_view::npos ? text.npos : newline - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);  // files written on Windows
    const auto bad = [&](const char* what) {
      return InputError(source + ": bad " + what + " line '" + std::string(line.substr(0, 80)) + "'");
    };
    const auto words = words_of(line);
    const std::string_view keyword = words.empty() ? std::string_view() : words[0];
    if (line_number == 0 && line != "ply") throw InputError(source + ": not a PLY file (the first line is not 'ply')");
    if (keyword == "end_header") {
      if (newline == std::string_view::npos) throw InputError(source + ": PLY header does not end with a line break");
      header.data_offset = newline + 1;
      break;
    }
    if (newline == std::string_view::npos)
      throw InputError(source + ": not a PLY file (no end_header line in its first " + std::to_string(kHeaderLimit) + " bytes)");
    start = newline + 1;

    if (keyword == "format") {
      const std::string_view name = words.size() > 1 ? words[1] : std::string_view();
      if (name == "ascii") header.format = PlyFormat::Ascii;
      else if (name == "binary_little_endian") header.format = PlyFormat::BinaryLittleEndian;
      else if (name == "binary_big_endian") header.format = PlyFormat::BinaryBigEndian;
      else throw InputError(source + ": PLY format '" + std::string(name) + "' is not a PLY format (ascii, binary_little_endian, binary_big_endian)");
      header.format_name = name;
      format_seen = true;
    } else if (keyword == "element") {
      PlyElement e;
      if (words.size() < 3) throw bad("element");
      e.name = words[1];
      const std::string_view count = words[2];
      const auto parsed = std::from_chars(count.data(), count.data() + count.size(), e.count);
      if (parsed.ec != std::errc() || parsed.ptr != count.data() + count.size())
        throw bad("element");
      header.elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (header.elements.empty()) throw InputError(source + ": property before any element");
      PlyProperty p;
      if (words.size() >= 2 && words[1] == "list") {
        if (words.size() < 5) throw bad("property");
        p.list = true;
        p.count_type = scalar_type(words[2], source);
        p.type = scalar_type(words[3], source);
        p.name = words[4];
      } else {
        if (words.size() < 3) throw bad("property");
        p.type = scalar_type(words[1], source);
        p.name = words[2];
      }
      header.elements.back().properties.push_back(std::move(p));
    } else if (keyword == "comment" || keyword == "obj_info") {
      const std::size_t text_start = line.find(keyword) + keyword.size();
      const std::size_t first = line.find_first_not_of(" \t", text_start);
      header.comments.emplace_back(first == std::string_view::npos ? std::string_view() : line.substr(first));
    }  // other lines: ignored, as PLY readers traditionally do
  }
  if (!format_seen) throw InputError(source + ": PLY header has no format line");
  return header;
}

}  // namespace nf::io
