// Strands as a USD stage in text form: an Xform "animal" holding one BasisCurves prim (linear), per-vertex
// widths, the colours per vertex (primvars:displayColor, linear) when the groom has them, the region of each
// strand as a uniform int primvar, and optionally the body as a Mesh prim.
// Read back (the curves only) by a parser of exactly that subset.
#include <cctype>
#include <charconv>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/io/strand_stream.hpp"
#include "engine/io/text_io.hpp"

namespace nf::io {
namespace {

// The numbers inside the brackets that follow `key` (parentheses and commas are separators).
std::vector<double> numbers_after(const std::string& text, const std::string& key, const std::string& where) {
  const std::size_t at = text.find(key + " ");
  if (at == std::string::npos) return {};
  const std::size_t equals = text.find('=', at);  // the key itself may contain brackets (point3f[])
  const std::size_t open = equals == std::string::npos ? equals : text.find('[', equals);
  const std::size_t close = open == std::string::npos ? open : text.find(']', open);
  if (close == std::string::npos) throw InputError(where + ": '" + key + "' has no [...] value");
  std::vector<double> out;
  const char* p = text.data() + open + 1;
  const char* end = text.data() + close;
  while (p < end) {
    if (*p == ',' || *p == '(' || *p == ')' || std::isspace(static_cast<unsigned char>(*p))) {
      ++p;
      continue;
    }
    double v;
    const auto r = std::from_chars(p, end, v);
    if (r.ec != std::errc()) throw InputError(where + ": '" + key + "' holds something that is not a number");
    out.push_back(v);
    p = r.ptr;
  }
  return out;
}

}  // namespace

void write_strands_usda(const std::filesystem::path& path, const StrandSet& s, float default_width) {
  s.validate(path.string());
  StrandStream stream = StrandStream::of(s);
  if (!stream.width) stream.width = [default_width](std::uint64_t, std::uint32_t) { return default_width; };
  write_strands_usda(path, stream);
}

namespace {

// `[a, b, c]` of `count` values, each written by `put(i)`, wrapped every so often so that text
// editors cope with the file.
template <class Put>
void put_array(std::ostream& out, std::uint64_t count, Put put) {
  out << '[';
  for (std::uint64_t i = 0; i < count; ++i) {
    if (i) out << ((i % 16) ? ", " : ",\n        ");
    put(i);
  }
  out << ']';
}

void put_tuple(std::ostream& out, const float* v, int n) {
  out << '(';
  for (int a = 0; a < n; ++a) {
    if (a) out << ", ";
    put_float(out, v[a]);
  }
  out << ')';
}

void put_extent(std::ostream& out, const float lo[3], const float hi[3]) {
  out << "        float3[] extent = [";
  put_tuple(out, lo, 3);
  out << ", ";
  put_tuple(out, hi, 3);
  out << "]\n";
}

void write_body_prim(std::ostream& out, const geometry::Mesh& m, std::span<const float> colors) {
  out << "    def Mesh \"body\"\n    {\n        uniform token subdivisionScheme = \"none\"\n        uniform token orientation = \"rightHanded\"\n";
  out << "        int[] faceVertexCounts = ";
  put_array(out, m.triangle_count(), [&](std::uint64_t) { out << '3'; });
  out << "\n        int[] faceVertexIndices = ";
  put_array(out, m.triangles.size(), [&](std::uint64_t i) { put_integer(out, m.triangles[i]); });
  out << "\n        point3f[] points = ";
  put_array(out, m.vertex_count(), [&](std::uint64_t i) { put_tuple(out, &m.positions[3 * i], 3); });
  out << "\n";
  float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (std::size_t v = 0; v < m.vertex_count(); ++v)
    for (int a = 0; a < 3; ++a) {
      const float x = m.positions[3 * v + std::size_t(a)];
      lo[a] = v ? std::min(lo[a], x) : x, hi[a] = v ? std::max(hi[a], x) : x;
    }
  put_extent(out, lo, hi);
  if (!m.normals.empty()) {
    out << "        normal3f[] normals = ";
    put_array(out, m.vertex_count(), [&](std::uint64_t i) { put_tuple(out, &m.normals[3 * i], 3); });
    out << " (\n            interpolation = \"vertex\"\n        )\n";
  }
  if (!m.regions.empty()) {
    out << "        int[] primvars:region = ";
    put_array(out, m.vertex_count(), [&](std::uint64_t i) { put_integer(out, m.regions[i]); });
    out << " (\n            interpolation = \"vertex\"\n        )\n";
  }
  if (!colors.empty()) {
    NF_CHECK(colors.size() == 3 * m.vertex_count(), "USD: body colours of another mesh");
    out << "        color3f[] primvars:displayColor = ";
    put_array(out, m.vertex_count(), [&](std::uint64_t i) { put_tuple(out, &colors[3 * i], 3); });
    out << " (\n            interpolation = \"vertex\"\n        )\n";
  }
  out << "    }\n";
}

}  // namespace

void write_strands_usda(const std::filesystem::path& path, const StrandStream& s, const UsdaScene& scene) {
  write_file_atomic(path, [&](std::ostream& out) {
    out << "#usda 1.0\n(\n    defaultPrim = \"animal\"\n    upAxis = \"Y\"\n";
    if (scene.meters_per_unit > 0) {
      out << "    metersPerUnit = ";
      put_float(out, float(scene.meters_per_unit));
      out << '\n';
    }
    out << "    doc = \"nf_gpu groom; " << frame_marker(s.frame) << "\"\n)\n\ndef Xform \"animal\" (\n    kind = \"component\"\n)\n{\n"
        << "    def BasisCurves \"fur\"\n    {\n        uniform token type = \"linear\"\n        uniform token wrap = \"nonperiodic\"\n"
        << "        int[] curveVertexCounts = ";
    put_array(out, s.strands, [&](std::uint64_t i) { put_integer(out, s.points_in(i)); });
    out << "\n        point3f[] points = [";
    std::uint64_t written = 0;
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    s.each_chunk([&](std::span<const float> xyz) {
      require_finite_points(path, xyz, 3 * written);
      for (std::size_t p = 0; p < xyz.size() / 3; ++p, ++written) {
        if (written) out << ((written % 16) ? ", " : ",\n        ");
        put_tuple(out, &xyz[3 * p], 3);
        for (int a = 0; a < 3; ++a) {
          const float x = xyz[3 * p + std::size_t(a)];
          lo[a] = written ? std::min(lo[a], x) : x, hi[a] = written ? std::max(hi[a], x) : x;
        }
      }
    });
    if (written != s.points) throw InternalError(path.string() + ": " + std::to_string(written) + " points streamed, " + std::to_string(s.points) + " announced");
    out << "]\n";
    put_extent(out, lo, hi);
    // A per-point attribute: `[a, b, ...]` over every strand's points, each written by put(strand, k).
    const auto put_per_point = [&](const char* declaration, const auto& put) {
      out << "        " << declaration << " = [";
      std::uint64_t p = 0;
      for (std::uint64_t i = 0; i < s.strands; ++i)
        for (std::uint32_t k = 0, n = s.points_in(i); k < n; ++k, ++p) {
          if (p) out << ((p % 16) ? ", " : ",\n        ");
          put(i, k);
        }
      out << "] (\n            interpolation = \"vertex\"\n        )\n";
    };
    if (s.width) put_per_point("float[] widths", [&](std::uint64_t i, std::uint32_t k) { put_float(out, s.width(i, k)); });
    if (s.color)  // USD's displayColor is linear; Blender's importer and usdview show it on the curves.
      put_per_point("color3f[] primvars:displayColor", [&](std::uint64_t i, std::uint32_t k) {
        const glm::vec3 c = s.color(i, k);
        put_tuple(out, &c.x, 3);
      });
    if (s.region) {
      out << "        int[] primvars:region = ";
      put_array(out, s.strands, [&](std::uint64_t i) { put_integer(out, s.region(i)); });
      out << " (\n            interpolation = \"uniform\"\n        )\n";
    }
    if (scene.root_face) {
      out << "        int[] primvars:rootFace = ";
      put_array(out, s.strands, [&](std::uint64_t i) { put_integer(out, scene.root_face(i)); });
      out << " (\n            interpolation = \"uniform\"\n        )\n";
    }
    if (scene.root_barycentric) {
      out << "        float3[] primvars:rootBarycentric = ";
      put_array(out, s.strands, [&](std::uint64_t i) {
        const glm::vec3 b = scene.root_barycentric(i);
        put_tuple(out, &b.x, 3);
      });
      out << " (\n            interpolation = \"uniform\"\n        )\n";
    }
    out << "    }\n";
    if (scene.body) write_body_prim(out, *scene.body, scene.body_colors);
    out << "}\n";
  });
}

StrandSet read_strands_usda(const std::filesystem::path& path) {
  const std::string where = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(where + ": cannot open");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.rfind("#usda", 0) != 0) throw InputError(where + ": not a text USD file (#usda header missing)");
  const std::size_t curves = text.find("def BasisCurves");
  if (curves == std::string::npos) throw InputError(where + ": no BasisCurves prim");
  // The curves' attributes: from their prim to the next prim (a body Mesh may follow).
  const std::size_t next = text.find("def ", curves + 4);
  const std::string prim = text.substr(curves, next == std::string::npos ? std::string::npos : next - curves);
  const auto counts = numbers_after(prim, "curveVertexCounts", where);
  const auto points = numbers_after(prim, "point3f[] points", where);
  const auto widths = numbers_after(prim, "float[] widths", where);
  const auto regions = numbers_after(prim, "primvars:region", where);
  const auto colors = numbers_after(prim, "primvars:displayColor", where);
  StrandSet s;
  if (!counts.empty()) s.offsets.push_back(0);
  for (double c : counts) {
    if (!(c >= 0 && c <= double(UINT32_MAX - s.offsets.back())) || c != std::floor(c))
      throw InputError(where + ": curveVertexCounts holds " + std::to_string(c));
    s.offsets.push_back(s.offsets.back() + std::uint32_t(c));
  }
  s.points.assign(points.begin(), points.end());
  s.thickness.assign(widths.begin(), widths.end());
  // Per-vertex colours only (what nf_gpu writes); a constant or per-curve displayColor from another
  // tool is left out rather than refused.
  if (colors.size() == points.size()) s.colors.assign(colors.begin(), colors.end());
  for (double r : regions) {
    if (!(r >= 0 && r <= 65535) || r != std::floor(r)) throw InputError(where + ": primvars:region holds " + std::to_string(r));
    s.regions.push_back(std::uint16_t(r));
  }
  s.validate(where);
  return s;
}

}  // namespace nf::io
