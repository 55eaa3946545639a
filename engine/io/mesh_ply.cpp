// Meshes as PLY. The reader takes ASCII and binary little-endian files with any element and
// property layout, keeps what the engine uses (positions, normals, an integer region / label,
// faces) and skips the rest; the writer produces binary little-endian. The header is parsed by
// ply_header.cpp, shared with the strand reader.
#include <cmath>
#include <cstring>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/io/binary_io.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/ply_header.hpp"

namespace nf::io {
namespace {

// Reads one value of `type`, from text tokens or from little-endian bytes.
class ValueReader {
 public:
  ValueReader(const std::vector<char>& bytes, std::size_t start, bool ascii, std::string where)
      : ascii_(ascii), where_(std::move(where)), binary_(bytes, where_) {
    binary_.seek(start);
    if (ascii) text_.str(std::string(bytes.begin() + std::ptrdiff_t(start), bytes.end()));
  }

  double read(PlyScalar type, const std::string& field) {
    if (ascii_) {
      double v;
      if (!(text_ >> v)) throw InputError(where_ + ": " + field + ": missing or not a number (file truncated?)");
      return v;
    }
    switch (type) {
      case PlyScalar::I8: return binary_.value<std::int8_t>(field);
      case PlyScalar::U8: return binary_.value<std::uint8_t>(field);
      case PlyScalar::I16: return binary_.value<std::int16_t>(field);
      case PlyScalar::U16: return binary_.value<std::uint16_t>(field);
      case PlyScalar::I32: return binary_.value<std::int32_t>(field);
      case PlyScalar::U32: return binary_.value<std::uint32_t>(field);
      case PlyScalar::F32: return binary_.value<float>(field);
      case PlyScalar::F64: return binary_.value<double>(field);
    }
    return 0;
  }

 private:
  bool ascii_;
  std::string where_;
  ByteReader binary_;
  std::istringstream text_;
};

}  // namespace

Mesh read_mesh_ply(const std::filesystem::path& path) {
  const std::string where = path.string();
  const std::vector<char> bytes = read_file_bytes(path);
  const PlyHeader header = parse_ply_header(bytes, where);
  if (header.format == PlyFormat::BinaryBigEndian)
    throw InputError(where + ": PLY format '" + header.format_name + "' is not read (ascii, binary_little_endian)");
  const bool ascii = header.format == PlyFormat::Ascii;

  Mesh m;
  ValueReader in(bytes, header.data_offset, ascii, where);
  for (const PlyElement& e : header.elements) {
    const bool vertex = e.name == "vertex", face = e.name == "face";
    // Guard the allocations below against counts no file of this size could hold.
    if (e.count > bytes.size()) throw InputError(where + ": element '" + e.name + "' count " + std::to_string(e.count) + " exceeds the file");
    bool has_normals = false, has_region = false;
    for (const PlyProperty& p : e.properties) {
      has_normals |= vertex && (p.name == "nx" || p.name == "ny" || p.name == "nz");
      has_region |= vertex && (p.name == "region" || p.name == "label" || p.name == "segment");
    }
    if (vertex) {
      m.positions.assign(e.count * 3, 0.f);
      if (has_normals) m.normals.assign(e.count * 3, 0.f);
      if (has_region) m.regions.assign(e.count, 0);
    }
    for (std::uint64_t i = 0; i < e.count; ++i) {
      for (const PlyProperty& p : e.properties) {
        const std::string field = "element '" + e.name + "' " + std::to_string(i) + " property '" + p.name + "'";
        if (p.list) {
          const double n = in.read(p.count_type, field + " count");
          if (!(n >= 0 && n <= 1e6) || n != std::floor(n))
            throw InputError(where + ": " + field + " has a list of " + std::to_string(n) + " items");
          std::vector<std::uint32_t> items(static_cast<std::size_t>(n));
          for (auto& item : items) {
            const double v = in.read(p.type, field);
            if (!(v >= 0 && v < 4294967296.0) || v != std::floor(v))
              throw InputError(where + ": " + field + " holds the index " + std::to_string(v));
            item = std::uint32_t(v);
          }
          if (face && (p.name == "vertex_indices" || p.name == "vertex_index")) {
            if (items.size() < 3) throw InputError(where + ": " + field + " has fewer than 3 corners");
            for (std::size_t k = 1; k + 1 < items.size(); ++k)
              m.triangles.insert(m.triangles.end(), {items[0], items[k], items[k + 1]});
          }
          continue;
        }
        const double v = in.read(p.type, field);
        if (!vertex) continue;
        if (p.name == "x") m.positions[3 * i] = float(v);
        else if (p.name == "y") m.positions[3 * i + 1] = float(v);
        else if (p.name == "z") m.positions[3 * i + 2] = float(v);
        else if (p.name == "nx") m.normals[3 * i] = float(v);
        else if (p.name == "ny") m.normals[3 * i + 1] = float(v);
        else if (p.name == "nz") m.normals[3 * i + 2] = float(v);
        else if (p.name == "region" || p.name == "label" || p.name == "segment") {
          if (!(v >= -2147483648.0 && v <= 2147483647.0) || v != std::floor(v))
            throw InputError(where + ": " + field + " is not an integer region (" + std::to_string(v) + ")");
          m.regions[i] = std::int32_t(v);
        }
      }
    }
  }
  m.validate(where);
  return m;
}

void write_mesh_ply(const std::filesystem::path& path, const Mesh& m) {
  m.validate(path.string());
  const bool normals = !m.normals.empty(), regions = !m.regions.empty();
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment nf_gpu mesh\ncomment " << frame_marker(FileFrame::scene) << "\nelement vertex " << m.vertex_count()
         << "\nproperty float x\nproperty float y\nproperty float z\n"
         << (normals ? "property float nx\nproperty float ny\nproperty float nz\n" : "")
         << (regions ? "property int region\n" : "") << "element face " << m.triangle_count()
         << "\nproperty list uchar uint vertex_indices\nend_header\n";
  write_file_atomic(path, [&](std::ostream& out) {
    out << header.str();
    for (std::uint64_t v = 0; v < m.vertex_count(); ++v) {
      out.write(reinterpret_cast<const char*>(&m.positions[3 * v]), 12);
      if (normals) out.write(reinterpret_cast<const char*>(&m.normals[3 * v]), 12);
      if (regions) out.write(reinterpret_cast<const char*>(&m.regions[v]), 4);
    }
    const std::uint8_t three = 3;
    for (std::uint64_t t = 0; t < m.triangle_count(); ++t) {
      out.write(reinterpret_cast<const char*>(&three), 1);
      out.write(reinterpret_cast<const char*>(&m.triangles[3 * t]), 12);
    }
  });
}

}  // namespace nf::io
