#include "engine/synth/fur_envelope.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/error.hpp"
#include "engine/geometry/distance_transform.hpp"
#include "engine/geometry/marching_cubes.hpp"
#include "engine/geometry/mesh_tools.hpp"
#include "engine/geometry/surface_sampling.hpp"

namespace nf::synth {

Envelope fur_envelope(const geometry::Mesh& body, const io::StrandSet& strands, const EnvelopeOptions& options) {
  if (body.vertex_count() == 0) throw InputError("fur envelope: the body mesh is empty");
  glm::vec3 lo(1e30f), hi(-1e30f);
  auto grow = [&](const std::vector<float>& xyz) {
    for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) {
      const glm::vec3 p(xyz[i], xyz[i + 1], xyz[i + 2]);
      lo = glm::min(lo, p), hi = glm::max(hi, p);
    }
  };
  grow(body.positions);
  grow(strands.points);
  const glm::vec3 extent = hi - lo;
  Envelope out;
  out.voxel = options.voxel > 0 ? options.voxel : std::max({extent.x, extent.y, extent.z}) / 300.0f;
  out.closing_radius = options.closing_radius > 0 ? options.closing_radius : 3.0f * out.voxel;
  const float v = out.voxel, r = out.closing_radius;
  const glm::vec3 origin = lo - (r + 3 * v);
  const glm::ivec3 dims = glm::ivec3(glm::ceil((extent + 2 * (r + 3 * v)) / v)) + 1;
  const std::size_t cells = std::size_t(dims.x) * dims.y * dims.z;
  if (cells > 400'000'000) throw UsageError("fur envelope: a " + std::to_string(dims.x) + "x" + std::to_string(dims.y) + "x" +
                                            std::to_string(dims.z) + " grid is too large; raise the voxel size");
  auto index = [&](glm::ivec3 c) { return (std::size_t(c.z) * dims.y + c.y) * dims.x + c.x; };
  auto cell_of = [&](glm::vec3 p) { return glm::clamp(glm::ivec3(glm::round((p - origin) / v)), glm::ivec3(0), dims - 1); };

  // Features: voxels touched by the body's surface or by a strand.
  std::vector<std::uint8_t> feature(cells, 0);
  const double area_per_sample = 0.25 * v * v;
  double area = 0;
  for (std::size_t t = 0; t < body.triangle_count(); ++t) {
    const std::uint32_t* tri = &body.triangles[3 * t];
    auto vtx = [&](int c) { return glm::vec3(body.positions[3 * tri[c]], body.positions[3 * tri[c] + 1], body.positions[3 * tri[c] + 2]); };
    area += 0.5 * glm::length(glm::cross(vtx(1) - vtx(0), vtx(2) - vtx(0)));
  }
  const auto samples = geometry::sample_surface(body, std::uint64_t(area / area_per_sample) + 1, 12345);
  for (std::size_t i = 0; i + 2 < samples.points.size(); i += 3)
    feature[index(cell_of({samples.points[i], samples.points[i + 1], samples.points[i + 2]}))] = 1;
  for (std::size_t i = 0; i < body.vertex_count(); ++i)
    feature[index(cell_of({body.positions[3 * i], body.positions[3 * i + 1], body.positions[3 * i + 2]}))] = 1;
  for (std::uint32_t s = 0; s < strands.strand_count(); ++s)
    for (std::uint32_t k = strands.offsets[s]; k + 1 < strands.offsets[s + 1]; ++k) {
      const glm::vec3 a(strands.points[3 * k], strands.points[3 * k + 1], strands.points[3 * k + 2]);
      const glm::vec3 b(strands.points[3 * k + 3], strands.points[3 * k + 4], strands.points[3 * k + 5]);
      const int steps = std::max(1, int(std::ceil(2.0f * glm::distance(a, b) / v)));
      for (int q = 0; q <= steps; ++q) feature[index(cell_of(a + (b - a) * (float(q) / float(steps))))] = 1;
    }

  // Dilate by r, then fill everything the outside cannot reach (the body's interior).
  const std::vector<float> to_feature = geometry::distance_transform(feature, dims, glm::vec3(v));
  std::vector<std::uint8_t> outside(cells, 0);
  std::vector<glm::ivec3> stack;
  auto try_push = [&](glm::ivec3 c) {
    const std::size_t i = index(c);
    if (outside[i] || to_feature[i] <= r) return;
    outside[i] = 1;
    stack.push_back(c);
  };
  for (int z = 0; z < dims.z; ++z)
    for (int y = 0; y < dims.y; ++y)
      for (int x = 0; x < dims.x; ++x)
        if (x == 0 || y == 0 || z == 0 || x == dims.x - 1 || y == dims.y - 1 || z == dims.z - 1) try_push({x, y, z});
  const glm::ivec3 steps[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  while (!stack.empty()) {
    const glm::ivec3 c = stack.back();
    stack.pop_back();
    for (const glm::ivec3& d : steps) {
      const glm::ivec3 q = c + d;
      if (glm::all(glm::greaterThanEqual(q, glm::ivec3(0))) && glm::all(glm::lessThan(q, dims))) try_push(q);
    }
  }
  // Erode by r: inside where the outside is farther than r. A 3^3 box filter softens the voxel
  // terraces of the distance field before extraction.
  const std::vector<float> to_outside = geometry::distance_transform(outside, dims, glm::vec3(v));
  std::vector<float> field(cells);
  for (std::size_t i = 0; i < cells; ++i) field[i] = std::min(r - to_outside[i], 2 * r);  // finite everywhere
  std::vector<float> smooth(field);
  for (int axis = 0; axis < 3; ++axis) {
    const glm::ivec3 d = steps[2 * axis];
    for (int z = 0; z < dims.z; ++z)
      for (int y = 0; y < dims.y; ++y)
        for (int x = 0; x < dims.x; ++x) {
          const glm::ivec3 c(x, y, z);
          const glm::ivec3 a = glm::clamp(c - d, glm::ivec3(0), dims - 1), b = glm::clamp(c + d, glm::ivec3(0), dims - 1);
          smooth[index(c)] = (field[index(a)] + field[index(c)] + field[index(b)]) / 3.0f;
        }
    field.swap(smooth);
  }
  out.mesh = geometry::marching_cubes(field.data(), dims, origin, glm::vec3(v), 0.0f);
  geometry::keep_largest_component(out.mesh);
  geometry::compute_vertex_normals(out.mesh);
  return out;
}

}  // namespace nf::synth
