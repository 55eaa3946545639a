// Strands as Wavefront OBJ: `v x y z` lines, then one `l i j k ...` polyline per strand (1-based).
#include <cctype>
#include <charconv>
#include <fstream>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/io/strand_files.hpp"
#include "engine/io/strand_stream.hpp"
#include "engine/io/text_io.hpp"

namespace nf::io {
void write_strands_obj(const std::filesystem::path& path, const StrandSet& s) {
  s.validate(path.string());
  write_strands_obj(path, StrandStream::of(s));
}

void write_strands_obj(const std::filesystem::path& path, const StrandStream& s) {
  write_file_atomic(path, [&](std::ostream& out) {
    out << "# nf_gpu strands: " << s.strands << " polylines, " << s.points << " points\n# " << frame_marker(s.frame) << "\n";
    std::uint64_t written = 0;
    s.each_chunk([&](std::span<const float> xyz) {
      require_finite_points(path, xyz, 3 * written);
      for (std::size_t p = 0; p < xyz.size() / 3; ++p) {
        out << "v ";
        put_xyz(out, &xyz[3 * p]);
        out << '\n';
      }
      written += xyz.size() / 3;
    });
    if (written != s.points) throw InternalError(path.string() + ": " + std::to_string(written) + " points streamed, " + std::to_string(s.points) + " announced");
    std::uint64_t next = 1;  // OBJ counts from 1
    for (std::uint64_t i = 0; i < s.strands; ++i) {
      const std::uint32_t n = s.points_in(i);
      out << 'l';
      for (std::uint32_t k = 0; k < n; ++k) {
        out << ' ';
        put_integer(out, next++);
      }
      out << '\n';
    }
  });
}

StrandSet read_strands_obj(const std::filesystem::path& path) {
  const std::string where = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(where + ": cannot open");
  std::vector<float> vertices;
  StrandSet s;
  s.offsets.push_back(0);
  std::string line;
  std::uint64_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.rfind("v ", 0) == 0) {
      std::istringstream words(line.substr(2));
      float xyz[3];
      if (!(words >> xyz[0] >> xyz[1] >> xyz[2]))
        throw InputError(where + ": line " + std::to_string(number) + ": a vertex needs three numbers");
      vertices.insert(vertices.end(), xyz, xyz + 3);
    } else if (line.rfind("l ", 0) == 0) {
      std::istringstream words(line.substr(2));
      long long index;
      while (words >> index) {
        if (!words.eof() && !std::isspace(words.peek()))
          throw InputError(where + ": line " + std::to_string(number) + ": a polyline lists vertex indices only");
        const long long n = std::int64_t(vertices.size() / 3);
        if (index < 0) index = n + index + 1;  // OBJ negative indices count back from the last vertex
        if (index < 1 || index > n)
          throw InputError(where + ": line " + std::to_string(number) + ": vertex index " + std::to_string(index) +
                           " is outside 1.." + std::to_string(n));
        s.points.insert(s.points.end(), vertices.begin() + (index - 1) * 3, vertices.begin() + index * 3);
      }
      if (!words.eof())
        throw InputError(where + ": line " + std::to_string(number) + ": '" + line + "' is not a list of vertex indices");
      s.offsets.push_back(std::uint32_t(s.points.size() / 3));
    }
  }
  if (s.offsets.size() == 1) s.offsets.clear();
  s.validate(where);
  return s;
}

}  // namespace nf::io
