// Strands as a USD stage in text form: one BasisCurves prim (linear), per-vertex widths, and the
// region of each strand as a uniform int primvar. Read back by a parser of exactly that subset.
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/io/text_io.hpp"

namespace nf::io {
namespace {

// The numbers inside the brackets that follow `key` (parentheses and commas are separators).
std::vector<double> numbers_after(const std::string& text, const std::string& key, const std::string& where) {
  const std::size_t at = text.find(key);
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
  write_file_atomic(path, [&](std::ostream& out) {
    out << "#usda 1.0\n(\n    defaultPrim = \"fur\"\n    upAxis = \"Y\"\n    doc = \"nf_gpu strands\"\n)\n\n"
        << "def BasisCurves \"fur\"\n{\n    uniform token type = \"linear\"\n    int[] curveVertexCounts = [";
    for (std::uint32_t i = 0; i < s.strand_count(); ++i) out << (i ? ", " : "") << s.points_in(i);
    out << "]\n    point3f[] points = [";
    for (std::uint64_t p = 0; p < s.point_count(); ++p) {
      out << (p ? ", (" : "(");
      put_xyz(out, &s.points[3 * p], ", ");
      out << ')';
    }
    out << "]\n    float[] widths = [";
    for (std::uint64_t p = 0; p < s.point_count(); ++p) {
      if (p) out << ", ";
      put_float(out, s.thickness.empty() ? default_width : s.thickness[p]);
    }
    out << "] (\n        interpolation = \"vertex\"\n    )\n";
    if (!s.regions.empty()) {
      out << "    int[] primvars:region = [";
      for (std::uint32_t i = 0; i < s.strand_count(); ++i) out << (i ? ", " : "") << s.regions[i];
      out << "] (\n        interpolation = \"uniform\"\n    )\n";
    }
    out << "}\n";
  });
}

StrandSet read_strands_usda(const std::filesystem::path& path) {
  const std::string where = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(where + ": cannot open");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.rfind("#usda", 0) != 0) throw InputError(where + ": not a text USD file (#usda header missing)");
  if (text.find("def BasisCurves") == std::string::npos) throw InputError(where + ": no BasisCurves prim");
  const auto counts = numbers_after(text, "curveVertexCounts", where);
  const auto points = numbers_after(text, "point3f[] points", where);
  const auto widths = numbers_after(text, "float[] widths", where);
  const auto regions = numbers_after(text, "primvars:region", where);
  StrandSet s;
  if (!counts.empty()) s.offsets.push_back(0);
  for (double c : counts) {
    if (!(c >= 0 && c <= double(UINT32_MAX - s.offsets.back())) || c != std::floor(c))
      throw InputError(where + ": curveVertexCounts holds " + std::to_string(c));
    s.offsets.push_back(s.offsets.back() + std::uint32_t(c));
  }
  s.points.assign(points.begin(), points.end());
  s.thickness.assign(widths.begin(), widths.end());
  for (double r : regions) {
    if (!(r >= 0 && r <= 65535) || r != std::floor(r)) throw InputError(where + ": primvars:region holds " + std::to_string(r));
    s.regions.push_back(std::uint16_t(r));
  }
  s.validate(where);
  return s;
}

}  // namespace nf::io
