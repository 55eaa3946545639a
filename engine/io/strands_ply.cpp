// Strands as binary little-endian PLY: vertices, the chains as `edge` elements (vertex1, vertex2)
// that Blender and most tools import, and a `strand` element (first, count, region) that keeps the
// strands exact for nf_gpu and anyone who reads it. Colours, when the groom has them, are the
// vertices' red, green and blue (8-bit sRGB). The header is parsed by ply_header.cpp, shared
// with the mesh reader.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/color.hpp"
#include "engine/io/binary_io.hpp"
#include "engine/io/ply_header.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/io/strand_stream.hpp"

namespace nf::io {

void write_strands_ply(const std::filesystem::path& path, const StrandSet& s) {
  s.validate(path.string());
  write_strands_ply(path, StrandStream::of(s));
}

void write_strands_ply(const std::filesystem::path& path, const StrandStream& s) {
  if (s.points > 0x7fffffffull)
    throw InputError(path.string() + ": " + std::to_string(s.points) + " points exceed the 32-bit signed indices of the PLY edge element; split the groom");
  const std::uint64_t edges = s.points - [&] {
    std::uint64_t nonempty = 0;
    for (std::uint64_t i = 0; i < s.strands; ++i) nonempty += s.points_in(i) ? 1 : 0;
    return nonempty;
  }();
  const bool thick = bool(s.width), colored = bool(s.color);
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment nf_gpu strands: polylines as vertex chains\ncomment " << frame_marker(s.frame)
         << (s.frame == FileFrame::exported ? " (metres, +y up, the animal facing +z; export.json beside it maps the scene to it)" : "") << "\n"
         << "element vertex " << s.points << "\nproperty float x\nproperty float y\nproperty float z\n"
         << (thick ? "property float thickness\n" : "")
         << (colored ? "property uchar red\nproperty uchar green\nproperty uchar blue\n" : "") << "element edge " << edges
         << "\nproperty int vertex1\nproperty int vertex2\n"
         << "element strand " << s.strands << "\nproperty int first\nproperty int count\nproperty ushort region\n"
         << "end_header\n";
  write_file_atomic(path, [&](std::ostream& out) {
    out << header.str();
    std::uint64_t written = 0;
    StrandCursor at(s);
    // A vertex record: x y z, the thickness, the colour as 8-bit sRGB (what Blender and most
    // viewers read as vertex colours).
    const std::size_t stride = 12 + (thick ? 4 : 0) + (colored ? 3 : 0);
    std::vector<char> records;
    s.each_chunk([&](std::span<const float> xyz) {
      require_finite_points(path, xyz, 3 * written);
      const std::size_t n = xyz.size() / 3;
      if (!thick && !colored) {
        out.write(reinterpret_cast<const char*>(xyz.data()), std::streamsize(xyz.size() * 4));
      } else {
        records.resize(stride * n);
        for (std::size_t p = 0; p < n; ++p, at.next()) {
          char* r = records.data() + stride * p;
          std::memcpy(r, &xyz[3 * p], 12);
          if (thick) {
            const float w = s.width(at.strand(), at.k());
            std::memcpy(r + 12, &w, 4);
          }
          if (colored) {
            const glm::vec3 c = color::linear_to_srgb(s.color(at.strand(), at.k()));
            for (int a = 0; a < 3; ++a) r[12 + (thick ? 4 : 0) + a] = char(std::uint8_t(std::lround(c[a] * 255.f)));
          }
        }
        out.write(records.data(), std::streamsize(records.size()));
      }
      written += n;
    });
    if (written != s.points) throw InternalError(path.string() + ": " + std::to_string(written) + " points streamed, " + std::to_string(s.points) + " announced");
    std::int64_t first = 0;
    for (std::uint64_t i = 0; i < s.strands; ++i) {
      const std::int64_t n = s.points_in(i);
      for (std::int64_t p = first; p + 1 < first + n; ++p) {
        const std::int32_t e[2] = {std::int32_t(p), std::int32_t(p + 1)};
        out.write(reinterpret_cast<const char*>(e), 8);
      }
      first += n;
    }
    first = 0;
    for (std::uint64_t i = 0; i < s.strands; ++i) {
      const std::int32_t fc[2] = {std::int32_t(first), std::int32_t(s.points_in(i))};
      const std::uint16_t region = s.region ? std::uint16_t(std::clamp(s.region(i), 0, 65535)) : 0;
      out.write(reinterpret_cast<const char*>(fc), 8);
      out.write(reinterpret_cast<const char*>(&region), 2);
      first += fc[1];
    }
  });
}

StrandSet read_strands_ply(const std::filesystem::path& path) {
  const std::string where = path.string();
  const std::vector<char> bytes = read_file_bytes(path);
  const PlyHeader header = parse_ply_header(bytes, where);
  if (header.format != PlyFormat::BinaryLittleEndian)
    throw InputError(where + ": only binary little-endian strand PLY files are read (format line)");
  // Element counts and the layout as "element:type:name" words.
  std::uint64_t vertices = 0, edges = 0, strands = 0;
  bool thick = false, colored = false, has_strand_element = false;
  std::string layout, order;
  for (const PlyElement& e : header.elements) {
    order += e.name + " ";
    if (e.name == "vertex") vertices = e.count;
    else if (e.name == "edge") edges = e.count;
    else if (e.name == "strand") strands = e.count, has_strand_element = true;
    else if (e.name == "face")
      throw InputError(where + ": this is a mesh (it has faces), not strands; a mesh is scored with `metrics --mesh FILE --ref FILE`");
    else throw InputError(where + ": unexpected element '" + e.name + "'");
    // The layout this reader supports is exactly the one write_strands_ply produces.
    for (const PlyProperty& p : e.properties) {
      layout += e.name + ":" + (p.list ? "list" : ply_type_name(p.type)) + ":" + p.name + " ";
      if (e.name == "vertex" && p.name == "thickness") thick = true;
      if (e.name == "vertex" && p.name == "red") colored = true;
    }
  }
  const std::string expected =
      std::string("vertex:float:x vertex:float:y vertex:float:z ") + (thick ? "vertex:float:thickness " : "") +
      (colored ? "vertex:uchar:red vertex:uchar:green vertex:uchar:blue " : "") +
      "edge:int:vertex1 edge:int:vertex2 " + (has_strand_element ? "strand:int:first strand:int:count strand:ushort:region " : "");
  if (layout != expected || (order != "vertex edge " && order != "vertex edge strand "))
    throw InputError(where + ": strand PLY layout is not the one nf_gpu reads (vertex x y z [thickness] as float [red green blue as uchar], "
                             "edge vertex1 vertex2 as int, strand first count as int and region as ushort)");
  ByteReader in(bytes, where);
  in.seek(header.data_offset);
  const std::uint64_t stride = 12 + (thick ? 4 : 0) + (colored ? 3 : 0);
  if (vertices > in.remaining() / stride) throw InputError(where + ": vertex count " + std::to_string(vertices) + " exceeds the file (truncated?)");
  std::vector<char> raw(vertices * stride);
  in.read(raw.data(), raw.size(), "vertex data");
  StrandSet s;
  s.points.resize(vertices * 3);
  if (thick) s.thickness.resize(vertices);
  if (colored) s.colors.resize(vertices * 3);
  for (std::uint64_t v = 0; v < vertices; ++v) {
    const char* r = raw.data() + stride * v;
    std::memcpy(&s.points[3 * v], r, 12);
    if (thick) std::memcpy(&s.thickness[v], r + 12, 4);
    if (colored)
      for (int a = 0; a < 3; ++a) s.colors[3 * v + std::size_t(a)] = color::srgb_to_linear(float(std::uint8_t(r[12 + (thick ? 4 : 0) + a])) / 255.f);
  }
  if (edges > in.remaining() / 8) throw InputError(where + ": edge count " + std::to_string(edges) + " exceeds the file (truncated?)");
  std::vector<std::int32_t> e(edges * 2);
  in.read(e.data(), e.size(), "edge data");
  if (has_strand_element) {
    s.offsets.push_back(0);
    for (std::uint64_t i = 0; i < strands; ++i) {
      const auto first = in.value<std::int32_t>("strand " + std::to_string(i) + " first");
      const auto count = in.value<std::int32_t>("strand " + std::to_string(i) + " count");
      const auto region = in.value<std::uint16_t>("strand " + std::to_string(i) + " region");
      const std::int64_t next = std::int64_t(first) + count;
      if (first != std::int64_t(s.offsets.back()) || count < 0 || next > std::int64_t(vertices))
        throw InputError(where + ": strand " + std::to_string(i) + " (first " + std::to_string(first) + ", count " +
                         std::to_string(count) + ") does not follow the previous strand");
      s.offsets.push_back(std::uint32_t(next));
      s.regions.push_back(region);
    }
  } else {
    // Plain vertex chains (files from other tools): consecutive edges (v, v+1) continue a strand,
    // and a strand starts right after the previous one ends.
    s.offsets.push_back(0);
    std::int64_t chain_end = -1;
    for (std::uint64_t i = 0; i < edges; ++i) {
      const std::int64_t a = e[2 * i], b = e[2 * i + 1];
      if (b != a + 1 || a < 0 || std::uint64_t(b) >= vertices)
        throw InputError(where + ": edge " + std::to_string(i) + " (" + std::to_string(a) + ", " + std::to_string(b) +
                         ") is not a step along a vertex chain");
      if (a != chain_end) {  // a new chain
        if (a != chain_end + 1) throw InputError(where + ": vertices before edge " + std::to_string(i) + " belong to no chain");
        if (chain_end >= 0) s.offsets.push_back(std::uint32_t(a));
      }
      chain_end = b;
    }
    if (vertices && std::uint64_t(chain_end + 1) != vertices)
      throw InputError(where + ": the last vertices belong to no chain");
    if (vertices) s.offsets.push_back(std::uint32_t(vertices));
    else s.offsets.clear();
  }
  if (in.remaining()) throw InputError(where + ": " + std::to_string(in.remaining()) + " bytes follow the last element");
  s.validate(where);
  return s;
}

}  // namespace nf::io
