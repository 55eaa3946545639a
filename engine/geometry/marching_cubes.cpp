#include "engine/geometry/marching_cubes.hpp"

#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/marching_cubes_table.hpp"
#include "engine/geometry/point_index.hpp"  // parallel_for

namespace nf::geometry {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

struct Field {
  const float* v;
  int nx, ny, nz;
  std::size_t sy, sz;  // strides of y and z
  float iso;
  glm::vec3 origin, h;

  float at(int x, int y, int z) const { return v[std::size_t(x) + sy * std::size_t(y) + sz * std::size_t(z)]; }
  bool inside(int x, int y, int z) const { return at(x, y, z) < iso; }

  // Central difference in world units, one-sided at the border (every axis has >= 2 samples).
  glm::dvec3 gradient(int x, int y, int z) const {
    auto diff = [&](int n, int i, float lo, float mid, float hi, double step) {
      if (i == 0) return double(hi - mid) / step;
      if (i == n - 1) return double(mid - lo) / step;
      return (double(hi) - double(lo)) / (2 * step);
    };
    const float c = at(x, y, z);
    return {diff(nx, x, x > 0 ? at(x - 1, y, z) : c, c, x + 1 < nx ? at(x + 1, y, z) : c, h.x),
            diff(ny, y, y > 0 ? at(x, y - 1, z) : c, c, y + 1 < ny ? at(x, y + 1, z) : c, h.y),
            diff(nz, z, z > 0 ? at(x, y, z - 1) : c, c, z + 1 < nz ? at(x, y, z + 1) : c, h.z)};
  }

  // Whether the edge from (x,y,z) along `axis` crosses the iso-value (the far end must exist).
  bool crosses(int x, int y, int z, int axis) const {
    return inside(x, y, z) != inside(x + (axis == 0), y + (axis == 1), z + (axis == 2));
  }

  // The vertex on a crossing edge: interpolated position and normal.
  void vertex(int x, int y, int z, int axis, float* pos, float* nrm) const {
    const int x1 = x + (axis == 0), y1 = y + (axis == 1), z1 = z + (axis == 2);
    const float a = at(x, y, z), b = at(x1, y1, z1);
    float t = (iso - a) / (b - a);  // b != a: exactly one of them is below iso
    t = t < 0.f ? 0.f : (t > 1.f ? 1.f : t);
    glm::vec3 p{float(x), float(y), float(z)};
    p[axis] += t;
    const glm::vec3 w = origin + p * h;
    pos[0] = w.x, pos[1] = w.y, pos[2] = w.z;
    const glm::dvec3 g = glm::mix(gradient(x, y, z), gradient(x1, y1, z1), double(t));
    const double len = glm::length(g);
    glm::dvec3 n(0.0);
    if (len > 0 && std::isfinite(len)) {
      n = g / len;
    } else {
      n[axis] = b > a ? 1.0 : -1.0;  // flat gradient: the edge's own direction towards outside
    }
    nrm[0] = float(n.x), nrm[1] = float(n.y), nrm[2] = float(n.z);
  }

  int cube_case(int x, int y, int z) const {
    int c = 0;
    for (int k = 0; k < 8; ++k)
      if (inside(x + (k & 1), y + ((k >> 1) & 1), z + ((k >> 2) & 1))) c |= 1 << k;
    return c;
  }
};

// Layers (z) handed out to parallel_for in units of kGrain items, so that its heuristic (about
// 1024 items per thread) gives one thread per layer up to the core count.
constexpr std::size_t kGrain = 1024;

template <class Body>
void for_each_layer(int layers, const Body& body) {
  parallel_for(std::size_t(layers) * kGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t z = (begin + kGrain - 1) / kGrain; z * kGrain < end; ++z) body(int(z));
  });
}

}  // namespace

geometry::Mesh marching_cubes(const float* values, glm::ivec3 dims, glm::vec3 origin, glm::vec3 voxel_size, float iso) {
  if (dims.x < 0 || dims.y < 0 || dims.z < 0)
    throw InputError("marching_cubes: negative grid size " + std::to_string(dims.x) + "x" + std::to_string(dims.y) +
                     "x" + std::to_string(dims.z));
  for (int a = 0; a < 3; ++a)
    if (!(voxel_size[a] > 0.f) || !std::isfinite(voxel_size[a]) || !std::isfinite(origin[a]))
      throw InputError("marching_cubes: voxel size and origin must be finite, voxel size positive (axis " +
                       std::to_string(a) + ": size " + std::to_string(voxel_size[a]) + ")");
  if (!std::isfinite(iso)) throw InputError("marching_cubes: the iso-value is not finite");
  geometry::Mesh mesh;
  if (dims.x < 2 || dims.y < 2 || dims.z < 2) return mesh;
  const std::size_t count = std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z);
  if (!values) throw InputError("marching_cubes: no values for a non-empty grid");
  require_finite(std::span<const float>(values, count), "marching_cubes: grid values");

  const Field f{values, dims.x, dims.y, dims.z, std::size_t(dims.x), std::size_t(dims.x) * std::size_t(dims.y), iso,
                origin, voxel_size};
  const int nx = dims.x, ny = dims.y, nz = dims.z;
  const MarchingCubesTable& table = marching_cubes_table();

  // Vertices owned by layer z: its x and y edges (y then x order, x edge before y edge), then the z
  // edges from layer z to z+1. Triangles of slab z: cubes between layers z and z+1, y then x order.
  auto for_xy_edges = [&](int z, auto&& emit) {
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        if (x + 1 < nx && f.crosses(x, y, z, 0)) emit(x, y, 0);
        if (y + 1 < ny && f.crosses(x, y, z, 1)) emit(x, y, 1);
      }
  };
  auto for_z_edges = [&](int z, auto&& emit) {
    if (z + 1 < nz)
      for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x)
          if (f.crosses(x, y, z, 2)) emit(x, y, 2);
  };

  std::vector<std::size_t> vertex_offset(std::size_t(nz) + 1, 0), triangle_offset(std::size_t(nz) + 1, 0);
  for_each_layer(nz, [&](int z) {
    std::size_t v = 0, t = 0;
    auto add = [&](int, int, int) { ++v; };
    for_xy_edges(z, add);
    for_z_edges(z, add);
    if (z + 1 < nz)
      for (int y = 0; y + 1 < ny; ++y)
        for (int x = 0; x + 1 < nx; ++x) t += table.triangle_count[f.cube_case(x, y, z)];
    vertex_offset[std::size_t(z) + 1] = v;
    triangle_offset[std::size_t(z) + 1] = t;
  });
  for (std::size_t z = 0; z < std::size_t(nz); ++z) {
    vertex_offset[z + 1] += vertex_offset[z];
    triangle_offset[z + 1] += triangle_offset[z];
  }
  if (vertex_offset.back() >= kNone)
    throw InputError("marching_cubes: the surface has " + std::to_string(vertex_offset.back()) +
                     " vertices, more than 32-bit indices allow");
  mesh.positions.resize(3 * vertex_offset.back());
  mesh.normals.resize(3 * vertex_offset.back());
  mesh.triangles.resize(3 * triangle_offset.back());

  for_each_layer(nz, [&](int z) {
    const std::size_t plane = std::size_t(nx) * std::size_t(ny);
    // Vertex index of the edge leaving grid point (x, y) of this layer / the next, per axis.
    std::vector<std::uint32_t> here[3], above[2];
    for (auto& m : here) m.assign(plane, kNone);
    std::uint32_t next = std::uint32_t(vertex_offset[std::size_t(z)]);
    auto make = [&](int x, int y, int axis) {
      f.vertex(x, y, z, axis, &mesh.positions[3 * std::size_t(next)], &mesh.normals[3 * std::size_t(next)]);
      here[axis][std::size_t(x) + std::size_t(nx) * std::size_t(y)] = next++;
    };
    for_xy_edges(z, make);
    for_z_edges(z, make);
    if (z + 1 >= nz) return;
    for (auto& m : above) m.assign(plane, kNone);
    std::uint32_t up = std::uint32_t(vertex_offset[std::size_t(z) + 1]);
    for_xy_edges(z + 1, [&](int x, int y, int axis) { above[axis][std::size_t(x) + std::size_t(nx) * std::size_t(y)] = up++; });

    std::uint32_t* out = mesh.triangles.data() + 3 * triangle_offset[std::size_t(z)];
    for (int y = 0; y + 1 < ny; ++y)
      for (int x = 0; x + 1 < nx; ++x) {
        const auto& row = table.triangles[f.cube_case(x, y, z)];
        for (int i = 0; i < kMcRowLength && row[i] >= 0; ++i) {
          const int e = row[i], axis = e / 4, low = table.edge_corners[e][0];
          const std::size_t at = std::size_t(x + (low & 1)) + std::size_t(nx) * std::size_t(y + ((low >> 1) & 1));
          // An edge starting on the upper layer runs along x or y (z edges start at layer z).
          const std::uint32_t index = (low >> 2) & 1 ? above[axis][at] : here[axis][at];
          NF_CHECK(index != kNone, "marching_cubes: a case uses an edge without a crossing");
          *out++ = index;
        }
      }
  });
  return mesh;
}

}  // namespace nf::geometry
