#include "engine/geometry/mesh_sdf.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"
#include "engine/geometry/closest_point.hpp"
#include "engine/geometry/mesh_tools.hpp"

namespace nf::geometry {
namespace {


struct Crossing {
  float position;  // along the line, in samples
  std::int8_t step;  // +1 entering the solid (front side to back side), -1 leaving
};

double cross2(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// Calls visit(line, position, step) for every lattice line of `axis` that crosses triangle t.
// Lattice points on a shared edge or vertex are counted once: the edge function of an edge is
// always evaluated from its lower-numbered vertex (so the two triangles sharing it see exact
// negatives), and a zero goes to the edge that a fixed direction rule owns.
template <class Visit>
void for_each_crossing(const Mesh& mesh, const std::vector<glm::dvec3>& g, std::size_t t, int axis, glm::ivec3 dims,
                       Visit&& visit) {
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  const std::uint32_t id[3]{mesh.triangles[3 * t], mesh.triangles[3 * t + 1], mesh.triangles[3 * t + 2]};
  double px[3], py[3], pa[3];
  for (int k = 0; k < 3; ++k) px[k] = g[id[k]][b], py[k] = g[id[k]][c], pa[k] = g[id[k]][axis];
  const double area = cross2(px[1] - px[0], py[1] - py[0], px[2] - px[0], py[2] - py[0]);
  if (area == 0 || !std::isfinite(area)) return;  // edge-on: its neighbours cover the lines near it
  const double flip = area > 0 ? 1.0 : -1.0;
  // n_axis < 0 (area < 0 in the cyclic (b, c) plane): the line, running along +axis, enters the solid.
  const std::int8_t step = area < 0 ? 1 : -1;
  const int b0 = std::max(0, int(std::ceil(std::min({px[0], px[1], px[2]}))));
  const int b1 = std::min(dims[b] - 1, int(std::floor(std::max({px[0], px[1], px[2]}))));
  const int c0 = std::max(0, int(std::ceil(std::min({py[0], py[1], py[2]}))));
  const int c1 = std::min(dims[c] - 1, int(std::floor(std::max({py[0], py[1], py[2]}))));
  for (int qc = c0; qc <= c1; ++qc)
    for (int qb = b0; qb <= b1; ++qb) {
      double e[3];
      bool inside = true;
      for (int k = 0; k < 3 && inside; ++k) {
        const int u = k, v = (k + 1) % 3;
        const int lo = id[u] < id[v] ? u : v, hi = lo == u ? v : u;
        double f = cross2(px[hi] - px[lo], py[hi] - py[lo], qb - px[lo], qc - py[lo]);
        if (lo != u) f = -f;
        f *= flip;  // counter-clockwise orientation: inside is positive
        if (f == 0) {
          // The edge as walked counter-clockwise; it owns its points when it runs "down" or
          // exactly "right". The other triangle walks it the other way, so exactly one owns them.
          const double dx = flip * (px[v] - px[u]), dy = flip * (py[v] - py[u]);
          inside = dy < 0 || (dy == 0 && dx > 0);
        } else {
          inside = f > 0;
        }
        e[k] = f;
      }
      if (!inside) continue;
      const double sum = std::abs(area);
      // Edge k (vertex k to k+1) weighs the opposite vertex k+2.
      const double position = (e[1] * pa[0] + e[2] * pa[1] + e[0] * pa[2]) / sum;
      visit(std::size_t(qc) * std::size_t(dims[b]) + std::size_t(qb), float(position), step);
    }
}

}  // namespace

GridSpec grid_around(glm::vec3 lo, glm::vec3 hi, int resolution, float padding) {
  const glm::vec3 extent = hi - lo;
  const float longest = std::max({extent.x, extent.y, extent.z});
  if (!(std::isfinite(longest) && longest > 0) || !std::isfinite(padding) || padding < 0)
    throw InputError("grid: the box is empty or not finite");
  if (resolution < 2) throw InputError("grid: resolution must be at least 2, got " + std::to_string(resolution));
  GridSpec g;
  g.voxel = longest / float(resolution - 1);
  g.origin = lo - glm::vec3(padding);
  for (int a = 0; a < 3; ++a) {
    const double n = std::ceil(double(extent[a] + 2 * padding) / double(g.voxel)) + 1;
    if (!(n <= 8192)) throw InputError("grid: " + std::to_string(n) + " samples along an axis (the padding is too wide for the resolution)");
    g.dims[a] = int(n);
  }
  return g;
}

std::vector<std::uint8_t> winding_inside(const Mesh& mesh, const GridSpec& grid, SignStats* stats) {
  const std::size_t n = grid.size();
  std::vector<std::uint8_t> in_votes(n, 0), out_votes(n, 0);
  std::vector<glm::dvec3> g(mesh.vertex_count());
  for (std::size_t v = 0; v < g.size(); ++v)
    g[v] = (glm::dvec3(mesh.position(v)) - glm::dvec3(grid.origin)) / double(grid.voxel);
  SignStats local;
  for (int axis = 0; axis < 3; ++axis) {
    const int b = (axis + 1) % 3, c = (axis + 2) % 3;
    const std::size_t lines = std::size_t(grid.dims[b]) * std::size_t(grid.dims[c]);
    std::vector<std::uint32_t> first(lines + 1, 0);
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
      for_each_crossing(mesh, g, t, axis, grid.dims, [&](std::size_t line, float, std::int8_t) { ++first[line + 1]; });
    for (std::size_t l = 0; l < lines; ++l) first[l + 1] += first[l];
    std::vector<Crossing> crossings(first[lines]);
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
      for_each_crossing(mesh, g, t, axis, grid.dims,
                        [&](std::size_t line, float p, std::int8_t s) { crossings[fill[line]++] = {p, s}; });
    std::vector<std::uint8_t> open(lines, 0);
    parallel_for(lines, [&](std::size_t l0, std::size_t l1) {
      for (std::size_t l = l0; l < l1; ++l) {
        const auto begin = crossings.begin() + first[l], end = crossings.begin() + first[l + 1];
        std::sort(begin, end, [](const Crossing& x, const Crossing& y) { return x.position < y.position; });
        int total = 0;
        for (auto it = begin; it != end; ++it) total += it->step;
        if (total != 0) {
          open[l] = 1;  // through a hole or a stray face: no vote
          continue;
        }
        glm::ivec3 q(0);
        q[b] = int(l % std::size_t(grid.dims[b])), q[c] = int(l / std::size_t(grid.dims[b]));
        int winding = 0;
        auto it = begin;
        for (int i = 0; i < grid.dims[axis]; ++i) {
          while (it != end && it->position < float(i)) winding += it->step, ++it;
          q[axis] = i;
          const std::size_t s = grid.index(q.x, q.y, q.z);
          if (winding != 0) ++in_votes[s];
          else ++out_votes[s];
        }
      }
    });
    local.lines += lines;
    for (std::uint8_t o : open) local.open_lines += o;
  }
  std::vector<std::uint8_t> inside(n);
  for (std::size_t s = 0; s < n; ++s) {
    inside[s] = in_votes[s] > out_votes[s] ? 1 : out_votes[s] > in_votes[s] ? 0 : 2;
    local.tied_samples += inside[s] == 2;
  }
  if (stats) *stats = local;
  return inside;
}

SignedDistanceGrid signed_distance_grid(const Mesh& mesh, const SdfOptions& options, const std::string& source) {
  mesh.validate(source);
  if (mesh.triangle_count() == 0) throw InputError(source + ": the mesh has no triangles");
  const Bounds box = mesh_bounds(mesh);
  const float longest = box.longest();
  if (!(longest > 0)) throw InputError(source + ": the mesh has no extent");
  if (options.resolution < 4) throw InputError(source + ": grid resolution must be at least 4");
  const float voxel = longest / float(options.resolution - 1);
  SignedDistanceGrid out;
  out.band = options.band > 0 ? options.band : 3 * voxel;
  const float padding = options.padding >= 0 ? options.padding : out.band + 2 * voxel;
  out.grid = grid_around(box.lo, box.hi, options.resolution, padding);
  const GridSpec& g = out.grid;
  const std::size_t n = g.size();
  std::vector<float> dist(n, std::numeric_limits<float>::infinity());
  out.closest.assign(n, kNoTriangle);

  const auto measure = [&](std::size_t s, glm::vec3 p, std::uint32_t t) {
    const glm::vec3 a = mesh.position(mesh.triangles[3 * std::size_t(t)]), b = mesh.position(mesh.triangles[3 * std::size_t(t) + 1]),
                    c = mesh.position(mesh.triangles[3 * std::size_t(t) + 2]);
    const float d = glm::length(p - closest_point_on_triangle(p, a, b, c).point);
    if (d < dist[s] && d <= out.band) dist[s] = d, out.closest[s] = t;
  };

  // Seeds: every sample within a voxel of a triangle's box, layer by layer (layers are independent).
  std::vector<std::vector<std::uint32_t>> layers(std::size_t(g.dims.z));
  std::vector<glm::ivec3> box_lo(mesh.triangle_count()), box_hi(mesh.triangle_count());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    glm::vec3 tl(std::numeric_limits<float>::max()), th(-std::numeric_limits<float>::max());
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 q = (mesh.position(mesh.triangles[3 * t + std::size_t(k)]) - g.origin) / g.voxel;
      tl = glm::min(tl, q), th = glm::max(th, q);
    }
    box_lo[t] = glm::max(glm::ivec3(glm::floor(tl)) - 1, glm::ivec3(0));
    box_hi[t] = glm::min(glm::ivec3(glm::ceil(th)) + 1, g.dims - 1);
    for (int k = box_lo[t].z; k <= box_hi[t].z; ++k) layers[std::size_t(k)].push_back(std::uint32_t(t));
  }
  parallel_for(layers.size(), [&](std::size_t k0, std::size_t k1) {
    for (std::size_t k = k0; k < k1; ++k)
      for (std::uint32_t t : layers[k])
        for (int j = box_lo[t].y; j <= box_hi[t].y; ++j)
          for (int i = box_lo[t].x; i <= box_hi[t].x; ++i) measure(g.index(i, j, int(k)), g.position(i, j, int(k)), t);
  }, 1);
  layers.clear();

  // Sweeps: each sample tries its line neighbours' closest triangles, forwards then backwards,
  // along x, y and z, twice.
  for (int round = 0; round < 2; ++round)
    for (int axis = 0; axis < 3; ++axis) {
      const int b = (axis + 1) % 3, c = (axis + 2) % 3;
      const std::size_t lines = std::size_t(g.dims[b]) * std::size_t(g.dims[c]);
      parallel_for(lines, [&](std::size_t l0, std::size_t l1) {
        for (std::size_t l = l0; l < l1; ++l) {
          glm::ivec3 q(0);
          q[b] = int(l % std::size_t(g.dims[b])), q[c] = int(l / std::size_t(g.dims[b]));
          const auto step = [&](int from, int to) {
            glm::ivec3 f = q, t = q;
            f[axis] = from, t[axis] = to;
            const std::uint32_t tri = out.closest[g.index(f.x, f.y, f.z)];
            const std::size_t s = g.index(t.x, t.y, t.z);
            if (tri != kNoTriangle && tri != out.closest[s]) measure(s, g.position(t.x, t.y, t.z), tri);
          };
          for (int i = 1; i < g.dims[axis]; ++i) step(i - 1, i);
          for (int i = g.dims[axis] - 2; i >= 0; --i) step(i + 1, i);
        }
      });
    }

  const std::vector<std::uint8_t> inside = winding_inside(mesh, g, &out.sign);
  out.distance.resize(n);
  parallel_for(std::size_t(g.dims.z), [&](std::size_t k0, std::size_t k1) {
    for (std::size_t k = k0; k < k1; ++k)
      for (int j = 0; j < g.dims.y; ++j)
        for (int i = 0; i < g.dims.x; ++i) {
          const std::size_t s = g.index(i, j, int(k));
          const float d = std::min(dist[s], out.band);
          bool in = inside[s] == 1;
          if (inside[s] == 2 && out.closest[s] != kNoTriangle) {  // a tie: the closest face's side
            const std::size_t t = out.closest[s];
            const glm::vec3 a = mesh.position(mesh.triangles[3 * t]), b = mesh.position(mesh.triangles[3 * t + 1]),
                            c = mesh.position(mesh.triangles[3 * t + 2]);
            const glm::vec3 p = g.position(i, j, int(k));
            in = glm::dot(p - closest_point_on_triangle(p, a, b, c).point, glm::cross(b - a, c - a)) < 0;
          }
          out.distance[s] = in ? -d : d;
        }
  }, 1);
  return out;
}

float sample_grid(const GridSpec& g, const std::vector<float>& values, glm::vec3 p) {
  const glm::vec3 q = glm::clamp((p - g.origin) / g.voxel, glm::vec3(0.f), glm::vec3(g.dims - 1));
  const glm::ivec3 i0 = glm::min(glm::ivec3(glm::floor(q)), glm::max(g.dims - 2, glm::ivec3(0)));
  const glm::vec3 f = q - glm::vec3(i0);
  float v = 0;
  for (int c = 0; c < 8; ++c) {
    const glm::ivec3 o(c & 1, (c >> 1) & 1, (c >> 2) & 1);
    const glm::ivec3 i = glm::min(i0 + o, g.dims - 1);
    const float w = (o.x ? f.x : 1 - f.x) * (o.y ? f.y : 1 - f.y) * (o.z ? f.z : 1 - f.z);
    v += w * values[g.index(i.x, i.y, i.z)];
  }
  return v;
}

}  // namespace nf::geometry
