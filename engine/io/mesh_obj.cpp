// Meshes as Wavefront OBJ: v, vn, f. Faces with more than three corners are fanned into triangles;
// `v/vt/vn` corner forms and negative (relative) indices are accepted.
#include <charconv>
#include <fstream>
#include <sstream>

#include "engine/core/atomic_file.hpp"
#include "engine/core/error.hpp"
#include "engine/io/mesh.hpp"
#include "engine/io/text_io.hpp"

namespace nf::io {
Mesh read_mesh_obj(const std::filesystem::path& path) {
  const std::string where = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(where + ": cannot open");
  Mesh m;
  std::vector<float> normals;
  std::vector<std::int64_t> corner_normal;  // per vertex: which vn it uses (-1: none)
  std::string line;
  std::uint64_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream words(line);
    std::string tag;
    words >> tag;
    if (tag == "v" || tag == "vn") {
      float xyz[3];
      if (!(words >> xyz[0] >> xyz[1] >> xyz[2]))
        throw InputError(where + ": line " + std::to_string(number) + ": '" + tag + "' needs three numbers");
      auto& target = tag == "v" ? m.positions : normals;
      target.insert(target.end(), xyz, xyz + 3);
      if (tag == "v") corner_normal.push_back(-1);
    } else if (tag == "f") {
      std::vector<std::uint32_t> face;
      std::string corner;
      while (words >> corner) {
        long long indices[3] = {0, 0, 0};
        std::size_t part = 0, start = 0;
        for (std::size_t i = 0; i <= corner.size() && part < 3; ++i) {
          if (i == corner.size() || corner[i] == '/') {
            if (i > start) {
              const auto r = std::from_chars(corner.data() + start, corner.data() + i, indices[part]);
              if (r.ec != std::errc() || r.ptr != corner.data() + i)
                throw InputError(where + ": line " + std::to_string(number) + ": bad face corner '" + corner + "'");
            }
            ++part;
            start = i + 1;
          }
        }
        const long long n = std::int64_t(m.positions.size() / 3);
        long long v = indices[0] < 0 ? n + indices[0] + 1 : indices[0];
        if (v < 1 || v > n)
          throw InputError(where + ": line " + std::to_string(number) + ": vertex index " + std::to_string(indices[0]) +
                           " is outside 1.." + std::to_string(n));
        if (indices[2] != 0) {
          const long long nn = std::int64_t(normals.size() / 3);
          const long long vn = indices[2] < 0 ? nn + indices[2] + 1 : indices[2];
          if (vn < 1 || vn > nn) throw InputError(where + ": line " + std::to_string(number) + ": normal index out of range");
          corner_normal[std::size_t(v - 1)] = vn - 1;
        }
        face.push_back(std::uint32_t(v - 1));
      }
      if (face.size() < 3) throw InputError(where + ": line " + std::to_string(number) + ": a face needs three corners");
      for (std::size_t k = 1; k + 1 < face.size(); ++k) m.triangles.insert(m.triangles.end(), {face[0], face[k], face[k + 1]});
    }
  }
  if (!normals.empty()) {
    m.normals.assign(m.positions.size(), 0.f);
    for (std::size_t v = 0; v < corner_normal.size(); ++v)
      if (corner_normal[v] >= 0)
        for (int a = 0; a < 3; ++a) m.normals[3 * v + a] = normals[std::size_t(3 * corner_normal[v] + a)];
  }
  m.validate(where);
  return m;
}

void write_mesh_obj(const std::filesystem::path& path, const Mesh& m) {
  m.validate(path.string());
  write_file_atomic(path, [&](std::ostream& out) {
    out << "# nf_gpu mesh: " << m.vertex_count() << " vertices, " << m.triangle_count() << " triangles\n# " << frame_marker(FileFrame::scene) << "\n";
    for (std::uint64_t v = 0; v < m.vertex_count(); ++v) {
      out << "v ";
      put_xyz(out, &m.positions[3 * v]);
      out << '\n';
    }
    for (std::uint64_t v = 0; v < (m.normals.empty() ? 0 : m.vertex_count()); ++v) {
      out << "vn ";
      put_xyz(out, &m.normals[3 * v]);
      out << '\n';
    }
    const bool with_normals = !m.normals.empty();
    for (std::uint64_t t = 0; t < m.triangle_count(); ++t) {
      out << 'f';
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = m.triangles[3 * t + k] + 1;
        out << ' ' << v;
        if (with_normals) out << "//" << v;
      }
      out << '\n';
    }
  });
}

}  // namespace nf::io
