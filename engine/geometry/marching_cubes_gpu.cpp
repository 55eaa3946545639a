#include "engine/geometry/marching_cubes_gpu.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/geometry/marching_cubes_table.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/gpu/scan.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::geometry {
namespace {

// Mirrors the push block of shaders/geometry/marching_cubes_count.comp.
struct CountPush {
  std::uint32_t nx, ny, nz, z0, count, values_z, values_shift, edges_shift, cells_shift;
  float iso;
};

// Mirrors the push block of shaders/geometry/marching_cubes_emit.comp.
struct EmitPush {
  std::uint32_t nx, ny, nz, z0, count, values_z, values_shift, edges_shift, cells_shift;
  std::uint32_t vertex_base, vertex_shift, triangle_base, triangle_shift;
  float iso;
  float origin[3];
  float h[3];
};

constexpr std::uint32_t kWorkgroup = 64;
constexpr std::uint32_t kNoIndex = 0xffffffffu;
// uints per case in the GPU table: NF_MC_ROW of shaders/include/nf_marching_cubes.glsl.
constexpr std::uint32_t kRow = 16;
static_assert(1 + 3 * kMcMaxTriangles <= int(kRow), "a case row holds its count and every triangle corner");

// The generated case table as the shaders read it: per case its triangle count, then one edge code
// per triangle corner (bits 0-1 the edge's axis, bits 2-4 its low corner), so that a shader finds
// the grid edge of a cube edge without the edge-corner table.
const std::vector<std::uint32_t>& gpu_table() {
  static const std::vector<std::uint32_t> packed = [] {
    const MarchingCubesTable& t = marching_cubes_table();
    std::vector<std::uint32_t> out(256 * kRow, 0);
    for (int cs = 0; cs < 256; ++cs) {
      std::uint32_t* row = &out[std::size_t(cs) * kRow];
      row[0] = t.triangle_count[cs];
      for (int i = 0; i < 3 * int(t.triangle_count[cs]); ++i) {
        const int e = t.triangles[cs][i];
        row[1 + i] = std::uint32_t(e / 4) | (std::uint32_t(t.edge_corners[e][0]) << 2);
      }
    }
    return out;
  }();
  return packed;
}

std::string size_text(glm::ivec3 dims) {
  return std::to_string(dims.x) + "x" + std::to_string(dims.y) + "x" + std::to_string(dims.z);
}

// The checks of marching_cubes(), plus the 32-bit numbering limits of the GPU path.
void check_grid(glm::ivec3 dims, glm::vec3 origin, glm::vec3 voxel_size, float iso) {
  if (dims.x < 0 || dims.y < 0 || dims.z < 0) throw InputError("marching_cubes_gpu: negative grid size " + size_text(dims));
  for (int a = 0; a < 3; ++a)
    if (!(voxel_size[a] > 0.f) || !std::isfinite(voxel_size[a]) || !std::isfinite(origin[a]))
      throw InputError("marching_cubes_gpu: voxel size and origin must be finite, voxel size positive (axis " +
                       std::to_string(a) + ": size " + std::to_string(voxel_size[a]) + ")");
  if (!std::isfinite(iso)) throw InputError("marching_cubes_gpu: the iso-value is not finite");
  if (dims.x < 2 || dims.y < 2 || dims.z < 2) return;
  const std::uint64_t points = std::uint64_t(dims.x) * std::uint64_t(dims.y) * std::uint64_t(dims.z);
  const std::uint64_t cells = std::uint64_t(dims.x - 1) * std::uint64_t(dims.y - 1) * std::uint64_t(dims.z - 1);
  if (3 * points >= (1ull << 32) || std::uint64_t(kMcMaxTriangles) * cells >= (1ull << 32))
    throw DeviceError("marching_cubes_gpu: a " + size_text(dims) +
                      " grid is too large: the GPU extractor numbers grid edges (3 per sample) and triangles (up to " +
                      std::to_string(kMcMaxTriangles) + " per cell) in 32 bits; use marching_cubes() on the CPU");
}

// A binding over 4-byte elements [first, first + count) of `base`, starting on the device's offset
// alignment: `shift` elements precede the first wanted one.
struct Window {
  gpu::BufferRange range;
  std::uint32_t shift = 0;
};

Window window(gpu::BufferRange base, std::uint64_t first, std::uint64_t count, std::uint64_t align) {
  const std::uint64_t at = base.offset + 4 * first;
  const std::uint64_t start = at / align * align;
  return {gpu::BufferRange{base.buffer, start, at - start + 4 * count}, std::uint32_t((at - start) / 4)};
}

struct Slab {
  std::uint64_t z0, z1;  // layers [z0, z1)
};

// Splits layers [0, nz) greedily into slabs whose largest window, elements(z0, z1) 4-byte elements
// plus the alignment slack, fits `budget` bytes.
template <class Size>
std::vector<Slab> plan_slabs(std::uint64_t nz, std::uint64_t budget, std::uint64_t align, const Size& elements,
                             const char* pass) {
  auto fits = [&](std::uint64_t z0, std::uint64_t z1) { return 4 * elements(z0, z1) + align <= budget; };
  std::vector<Slab> slabs;
  for (std::uint64_t z0 = 0, z1 = 0; z0 < nz; z0 = z1) {
    z1 = z0 + 1;
    if (!fits(z0, z1))
      throw DeviceError(std::string("marching_cubes_gpu: the ") + pass + " pass over z-layer " + std::to_string(z0) +
                        " alone needs a binding of " + std::to_string(4 * elements(z0, z1) + align) +
                        " bytes, more than the " + std::to_string(budget) +
                        " bytes allowed (maxStorageBufferRange); use a coarser grid or marching_cubes() on the CPU");
    while (z1 < nz && fits(z0, z1 + 1)) ++z1;
    slabs.push_back({z0, z1});
  }
  return slabs;
}

}  // namespace

geometry::Mesh marching_cubes_gpu(gpu::Context& context, gpu::BufferRange values, glm::ivec3 dims, glm::vec3 origin,
                            glm::vec3 voxel_size, float iso, const MarchingCubesGpuOptions& options) {
  check_grid(dims, origin, voxel_size, iso);
  geometry::Mesh mesh;
  if (dims.x < 2 || dims.y < 2 || dims.z < 2) return mesh;
  const std::uint64_t nx = std::uint64_t(dims.x), ny = std::uint64_t(dims.y), nz = std::uint64_t(dims.z);
  const std::uint64_t plane = nx * ny, points = plane * nz;
  if (!values.buffer) throw InputError("marching_cubes_gpu: no values for a non-empty grid");
  gpu::require_bytes(values, 4 * points, "marching_cubes_gpu: grid values");
  if (values.offset % 4)
    throw InternalError("marching_cubes_gpu: grid values start at byte " + std::to_string(values.offset) +
                        ", not on a float");

  const gpu::DeviceLimits& limits = context.info().limits;
  std::uint64_t budget = std::min<std::uint64_t>(limits.max_storage_buffer_range, 1ull << 32);
  if (options.max_binding_bytes) budget = std::min(budget, options.max_binding_bytes);
  const std::uint64_t align = std::max<std::uint64_t>(4, limits.min_storage_buffer_offset_alignment);

  const gpu::Kernel& count_kernel = context.kernel("geometry/marching_cubes_count", {{0, kWorkgroup}});
  const gpu::Kernel& emit_kernel = context.kernel("geometry/marching_cubes_emit", {{0, kWorkgroup}});
  const gpu::Buffer<std::uint32_t> table(context, std::span<const std::uint32_t>(gpu_table()), "marching cubes table");
  // Edge flags (3 per sample: +x, +y, +z), scanned in place into vertex ids; cell triangle counts
  // (one per sample: the cell whose lowest corner it is), scanned in place into first triangles.
  gpu::Buffer<std::uint32_t> edges(context, 3 * points, "marching cubes edge ids");
  gpu::Buffer<std::uint32_t> cells(context, points, "marching cubes cell triangles");
  gpu::Buffer<std::uint32_t> first_bad(context, 1, "marching cubes first bad sample");
  gpu::Buffer<std::uint32_t> vertex_total(context, 1, "marching cubes vertex total");
  gpu::Buffer<std::uint32_t> triangle_total(context, 1, "marching cubes triangle total");
  // Per layer z: vertices and triangles of the layers below it, to size the emit pass's slabs.
  gpu::Buffer<std::uint32_t> layer_offsets(context, 2 * nz, "marching cubes layer offsets");

  {
    gpu::Stream stream(context);
    // Count slabs: the edge flags are the largest window, the values need one layer above the slab.
    const auto count_slabs = plan_slabs(nz, budget, align, [&](std::uint64_t z0, std::uint64_t z1) {
      return std::max(3 * (z1 - z0) * plane, (std::min(z1 + 1, nz) - z0) * plane);
    }, "count");
    {
      gpu::ScopedPass pass(stream, "geometry/marching_cubes_count");
      stream.fill(first_bad, kNoIndex);
      for (const Slab& s : count_slabs) {
        const std::uint64_t n = (s.z1 - s.z0) * plane;
        const Window v = window(values, s.z0 * plane, (std::min(s.z1 + 1, nz) - s.z0) * plane, align);
        const Window e = window(edges, 3 * s.z0 * plane, 3 * n, align);
        const Window c = window(cells, s.z0 * plane, n, align);
        const CountPush push{.nx = std::uint32_t(nx),
                             .ny = std::uint32_t(ny),
                             .nz = std::uint32_t(nz),
                             .z0 = std::uint32_t(s.z0),
                             .count = std::uint32_t(n),
                             .values_z = std::uint32_t(s.z0),
                             .values_shift = v.shift,
                             .edges_shift = e.shift,
                             .cells_shift = c.shift,
                             .iso = iso};
        stream.dispatch(count_kernel, {v.range, table.whole(), e.range, c.range, first_bad.whole()}, push, gpu::Elements(n));
      }
      gpu::exclusive_scan_flags(stream, edges, edges, vertex_total);
      gpu::exclusive_scan(stream, cells, cells, triangle_total);
      // The scans at each layer's first sample: vertex ids run in sample order, so they are the
      // counts of everything below the layer.
      for (std::uint64_t z = 0; z < nz; ++z) {
        stream.copy(edges.range(3 * z * plane, 1), layer_offsets.range(z, 1));
        stream.copy(cells.range(z * plane, 1), layer_offsets.range(nz + z, 1));
      }
    }
    stream.submit_and_wait();
  }

  const std::uint32_t bad = first_bad.download()[0];
  if (bad != kNoIndex) {
    float sample = 0.f;
    values.buffer->read_bytes(values.offset + 4 * std::uint64_t(bad), &sample, 4);
    std::ostringstream os;
    os << "marching_cubes_gpu: grid values: element " << bad << " is " << sample << " (NaN and Inf are not accepted)";
    throw InputError(os.str());
  }
  const std::uint64_t vertex_count = vertex_total.download()[0], triangle_count = triangle_total.download()[0];
  if (vertex_count == 0 && triangle_count == 0) return mesh;
  const std::vector<std::uint32_t> offsets = layer_offsets.download();
  std::vector<std::uint64_t> vertex_at(nz + 1), triangle_at(nz + 1);
  for (std::uint64_t z = 0; z < nz; ++z) vertex_at[z] = offsets[z], triangle_at[z] = offsets[nz + z];
  vertex_at[nz] = vertex_count, triangle_at[nz] = triangle_count;
  for (std::uint64_t z = 0; z < nz; ++z)
    NF_CHECK(vertex_at[z] <= vertex_at[z + 1] && triangle_at[z] <= triangle_at[z + 1],
             "marching_cubes_gpu: layer offsets decrease at layer " + std::to_string(z));

  // Emit slabs: the values need one layer below (gradients) and two above (the +z edges' far
  // gradients), the edge ids one above (the cells' top faces); outputs are the slab's own.
  const auto emit_slabs = plan_slabs(nz, budget, align, [&](std::uint64_t z0, std::uint64_t z1) {
    return std::max({(std::min(z1 + 2, nz) - (z0 ? z0 - 1 : 0)) * plane, 3 * (std::min(z1 + 1, nz) - z0) * plane,
                     3 * (vertex_at[z1] - vertex_at[z0]), 3 * (triangle_at[z1] - triangle_at[z0])});
  }, "emit");
  gpu::Buffer<float> positions(context, 3 * vertex_count, "marching cubes positions");
  gpu::Buffer<float> normals(context, 3 * vertex_count, "marching cubes normals");
  gpu::Buffer<std::uint32_t> triangles(context, 3 * triangle_count, "marching cubes triangles");
  {
    gpu::Stream stream(context);
    {
      gpu::ScopedPass pass(stream, "geometry/marching_cubes_emit");
      for (const Slab& s : emit_slabs) {
        const std::uint64_t n = (s.z1 - s.z0) * plane, below = s.z0 ? s.z0 - 1 : 0;
        const std::uint64_t v0 = vertex_at[s.z0], v1 = vertex_at[s.z1];
        const std::uint64_t t0 = triangle_at[s.z0], t1 = triangle_at[s.z1];
        const Window v = window(values, below * plane, (std::min(s.z1 + 2, nz) - below) * plane, align);
        const Window e = window(edges, 3 * s.z0 * plane, 3 * (std::min(s.z1 + 1, nz) - s.z0) * plane, align);
        const Window c = window(cells, s.z0 * plane, n, align);
        const Window p = window(positions, 3 * v0, 3 * (v1 - v0), align);
        const Window nr = window(normals, 3 * v0, 3 * (v1 - v0), align);
        const Window t = window(triangles, 3 * t0, 3 * (t1 - t0), align);
        NF_CHECK(p.shift == nr.shift, "marching_cubes_gpu: positions and normals windows differ");
        const EmitPush push{.nx = std::uint32_t(nx),
                            .ny = std::uint32_t(ny),
                            .nz = std::uint32_t(nz),
                            .z0 = std::uint32_t(s.z0),
                            .count = std::uint32_t(n),
                            .values_z = std::uint32_t(below),
                            .values_shift = v.shift,
                            .edges_shift = e.shift,
                            .cells_shift = c.shift,
                            .vertex_base = std::uint32_t(v0),
                            .vertex_shift = p.shift,
                            .triangle_base = std::uint32_t(t0),
                            .triangle_shift = t.shift,
                            .iso = iso,
                            .origin = {origin.x, origin.y, origin.z},
                            .h = {voxel_size.x, voxel_size.y, voxel_size.z}};
        stream.dispatch(emit_kernel, {v.range, table.whole(), e.range, c.range, p.range, nr.range, t.range}, push,
                        gpu::Elements(n));
      }
    }
    stream.submit_and_wait();
  }
  mesh.positions = positions.download();
  mesh.normals = normals.download();
  mesh.triangles = triangles.download();
  return mesh;
}

geometry::Mesh marching_cubes_gpu(gpu::Context& context, const std::vector<float>& values, glm::ivec3 dims, glm::vec3 origin,
                            glm::vec3 voxel_size, float iso, const MarchingCubesGpuOptions& options) {
  check_grid(dims, origin, voxel_size, iso);
  const std::uint64_t points = std::uint64_t(dims.x) * std::uint64_t(dims.y) * std::uint64_t(dims.z);
  if (values.size() != points)
    throw InputError("marching_cubes_gpu: " + std::to_string(values.size()) + " values for a " + size_text(dims) +
                     " grid of " + std::to_string(points) + " samples");
  if (dims.x < 2 || dims.y < 2 || dims.z < 2) return {};
  const gpu::Buffer<float> device(context, std::span<const float>(values), "marching cubes grid values");
  return marching_cubes_gpu(context, device, dims, origin, voxel_size, iso, options);
}

}  // namespace nf::geometry
