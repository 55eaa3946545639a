#include "engine/geometry/vertex_smoothing.hpp"

#include <algorithm>

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"

namespace nf::geometry {

std::vector<std::vector<std::uint32_t>> vertex_neighbours(const Mesh& mesh) {
  std::vector<std::vector<std::uint32_t>> out(mesh.vertex_count());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.triangles[3 * t + std::size_t(k)], b = mesh.triangles[3 * t + std::size_t(k + 1) % 3];
      out[a].push_back(b), out[b].push_back(a);
    }
  for (auto& n : out) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  return out;
}

void smooth_vertex_values(const Mesh& mesh, std::vector<float>& values, int channels, int iterations,
                          const std::vector<std::uint8_t>& active) {
  const std::size_t nv = mesh.vertex_count(), ch = std::size_t(channels);
  NF_CHECK(values.size() == nv * ch, "smooth_vertex_values: one value per vertex and channel");
  NF_CHECK(active.empty() || active.size() == nv, "smooth_vertex_values: one flag per vertex");
  if (iterations <= 0 || nv == 0) return;
  const auto neighbours = vertex_neighbours(mesh);
  const auto is_active = [&](std::size_t v) { return active.empty() || active[v] != 0; };
  std::vector<float> next(values.size());
  for (int it = 0; it < iterations; ++it) {
    parallel_for(nv, [&](std::size_t v0, std::size_t v1) {
      for (std::size_t v = v0; v < v1; ++v) {
        for (std::size_t c = 0; c < ch; ++c) next[v * ch + c] = values[v * ch + c];
        if (!is_active(v)) continue;
        int count = 1;
        for (std::uint32_t n : neighbours[v]) {
          if (!is_active(n)) continue;
          for (std::size_t c = 0; c < ch; ++c) next[v * ch + c] += values[std::size_t(n) * ch + c];
          ++count;
        }
        for (std::size_t c = 0; c < ch; ++c) next[v * ch + c] /= float(count);
      }
    });
    values.swap(next);
  }
}

}  // namespace nf::geometry
