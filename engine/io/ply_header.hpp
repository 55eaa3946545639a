#pragma once
// The header of a PLY file, parsed once for the mesh and the strand readers: the format line, the
// elements with their counts, the properties with their types (scalars and lists) and the comments.
// Each reader then decides which formats and layouts it reads.
#include <cstdint>
#include <string>
#include <vector>

namespace nf::io {

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };
enum class PlyScalar { I8, U8, I16, U16, I32, U32, F32, F64 };

struct PlyProperty {
  std::string name;
  PlyScalar type = PlyScalar::F32;  // of a list: the type of its items
  bool list = false;
  PlyScalar count_type = PlyScalar::U8;  // of a list: the type of its length
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::Ascii;
  std::string format_name;  // as written: "ascii", "binary_little_endian", "binary_big_endian"
  std::vector<PlyElement> elements;
  std::vector<std::string> comments;  // comment and obj_info lines, without the keyword
  std::size_t data_offset = 0;        // the first byte after the end_header line
};

// Parses the header at the start of `bytes` (within its first 64 KiB). Throws InputError naming
// `source`: "not a PLY file" (no 'ply' first line or no end_header line), "PLY header does not end
// with a line break", "PLY header has no format line", "PLY format 'x' is not read", "bad element
// line '...'", "bad property line '...'", "property before any element", "unknown PLY property type".
PlyHeader parse_ply_header(const std::vector<char>& bytes, const std::string& source);

// The type's canonical name ("char", "uchar", "short", "ushort", "int", "uint", "float", "double").
const char* ply_type_name(PlyScalar type);

}  // namespace nf::io
