#include "engine/geometry/mesh_tools.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/error.hpp"

namespace nf::geometry {
namespace {

void check_indices(const geometry::Mesh& mesh, const char* what) {
  const std::uint64_t n = mesh.vertex_count();
  for (std::uint32_t v : mesh.triangles) NF_CHECK(v < n, std::string(what) + ": a face uses a vertex past the end");
}

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];  // path halving
  return v;
}

}  // namespace

std::size_t keep_largest_component(geometry::Mesh& mesh) {
  check_indices(mesh, "keep_largest_component");
  const std::size_t nv = mesh.vertex_count(), nt = mesh.triangle_count();
  std::vector<std::uint32_t> parent(nv);
  std::iota(parent.begin(), parent.end(), 0u);
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t a = find_root(parent, mesh.triangles[3 * t]);
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t b = find_root(parent, mesh.triangles[3 * t + k]);
      if (a != b) parent[b] = a;
    }
  }
  std::vector<std::size_t> size(nv, 0);
  std::size_t components = 0, best_size = 0;
  std::uint32_t best = 0;
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t r = find_root(parent, mesh.triangles[3 * t]);
    if (size[r]++ == 0) ++components;
    best_size = std::max(best_size, size[r]);
  }
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t r = find_root(parent, mesh.triangles[3 * t]);
    if (size[r] == best_size) {
      best = r;
      break;
    }
  }

  std::vector<std::uint32_t> remap(nv, std::uint32_t(-1));
  std::vector<std::uint32_t> triangles;
  triangles.reserve(3 * best_size);
  for (std::size_t t = 0; t < nt; ++t)
    if (find_root(parent, mesh.triangles[3 * t]) == best)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = mesh.triangles[3 * t + k];
        triangles.push_back(v);
        remap[v] = 0;  // used: numbered below, in vertex order
      }
  const bool has_normals = mesh.normals.size() == mesh.positions.size(), has_regions = mesh.regions.size() == nv;
  std::vector<float> positions, normals;
  std::vector<std::int32_t> regions;
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (remap[v] != 0) continue;  // unused
    remap[v] = next++;
    positions.insert(positions.end(), mesh.positions.begin() + std::ptrdiff_t(3 * v),
                     mesh.positions.begin() + std::ptrdiff_t(3 * v + 3));
    if (has_normals)
      normals.insert(normals.end(), mesh.normals.begin() + std::ptrdiff_t(3 * v), mesh.normals.begin() + std::ptrdiff_t(3 * v + 3));
    if (has_regions) regions.push_back(mesh.regions[v]);
  }
  for (auto& v : triangles) v = remap[v];
  mesh.positions = std::move(positions);
  mesh.triangles = std::move(triangles);
  if (has_normals) mesh.normals = std::move(normals);
  else mesh.normals.clear();
  if (has_regions) mesh.regions = std::move(regions);
  else mesh.regions.clear();
  return components;
}

void compute_vertex_normals(geometry::Mesh& mesh) {
  check_indices(mesh, "compute_vertex_normals");
  const std::size_t nv = mesh.vertex_count();
  std::vector<glm::dvec3> sum(nv, glm::dvec3(0.0));
  auto position = [&](std::uint32_t v) {
    return glm::dvec3(mesh.positions[3 * std::size_t(v)], mesh.positions[3 * std::size_t(v) + 1],
                      mesh.positions[3 * std::size_t(v) + 2]);
  };
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::uint32_t* tri = &mesh.triangles[3 * t];
    const glm::dvec3 p0 = position(tri[0]);
    const glm::dvec3 n = glm::cross(position(tri[1]) - p0, position(tri[2]) - p0);  // |n| = 2 * area
    for (int k = 0; k < 3; ++k) sum[tri[k]] += n;
  }
  mesh.normals.assign(3 * nv, 0.f);
  for (std::size_t v = 0; v < nv; ++v) {
    const double len = glm::length(sum[v]);
    if (!(len > 0) || !std::isfinite(len)) continue;
    for (int k = 0; k < 3; ++k) mesh.normals[3 * v + std::size_t(k)] = float(sum[v][k] / len);
  }
}

std::vector<double> vertex_areas(const geometry::Mesh& mesh) {
  std::vector<double> area(mesh.vertex_count(), 0.0);
  for (std::size_t f = 0; f < mesh.triangle_count(); ++f) {
    const std::uint32_t* t = &mesh.triangles[3 * f];
    const glm::dvec3 a(mesh.position(t[0])), b(mesh.position(t[1])), c(mesh.position(t[2]));
    const double third = glm::length(glm::cross(b - a, c - a)) / 6.0;
    for (int k = 0; k < 3; ++k) area[t[k]] += third;
  }
  return area;
}

Bounds mesh_bounds(const geometry::Mesh& mesh) {
  Bounds b;
  if (mesh.vertex_count() == 0) return b;
  b.lo = b.hi = mesh.position(0);
  for (std::uint64_t v = 1; v < mesh.vertex_count(); ++v) b.lo = glm::min(b.lo, mesh.position(v)), b.hi = glm::max(b.hi, mesh.position(v));
  return b;
}

bool is_closed_manifold(const geometry::Mesh& mesh) {
  const std::uint64_t nv = mesh.vertex_count();
  const std::size_t nt = mesh.triangle_count();
  std::vector<std::uint64_t> edges;  // directed: from << 32 | to
  edges.reserve(3 * nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t* tri = &mesh.triangles[3 * t];
    if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv) return false;
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) return false;
    for (int k = 0; k < 3; ++k) edges.push_back(std::uint64_t(tri[k]) << 32 | tri[(k + 1) % 3]);
  }
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return false;  // a directed edge twice
  for (std::uint64_t e : edges)
    if (!std::binary_search(edges.begin(), edges.end(), (e << 32) | (e >> 32))) return false;  // no twin

  // Around vertex a, triangle (a, b, c) steps from neighbour b to c; with the edge test passed this
  // is a permutation of a's neighbours, which must be one cycle.
  std::vector<std::uint32_t> start(nv + 1, 0);
  for (std::uint32_t v : mesh.triangles) ++start[v + 1];
  for (std::uint64_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<std::pair<std::uint32_t, std::uint32_t>> steps(3 * nt);
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t* tri = &mesh.triangles[3 * t];
    for (int k = 0; k < 3; ++k) steps[fill[tri[k]]++] = {tri[(k + 1) % 3], tri[(k + 2) % 3]};
  }
  for (std::uint64_t v = 0; v < nv; ++v) {
    const auto first = steps.begin() + start[v], last = steps.begin() + start[v + 1];
    if (first == last) continue;
    std::sort(first, last);
    std::uint32_t at = first->first;
    std::size_t walked = 0;
    do {
      const auto it = std::lower_bound(first, last, std::make_pair(at, std::uint32_t(0)));
      if (it == last || it->first != at) return false;
      at = it->second;
      ++walked;
    } while (at != first->first && walked <= std::size_t(last - first));
    if (walked != std::size_t(last - first)) return false;
  }
  return true;
}

void transform_points(std::vector<float>& xyz, const glm::dmat4& similarity) {
  for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) {
    const glm::dvec4 p = similarity * glm::dvec4(xyz[i], xyz[i + 1], xyz[i + 2], 1.0);
    for (std::size_t a = 0; a < 3; ++a) xyz[i + a] = float(p[int(a)]);
  }
}

void transform_mesh(geometry::Mesh& mesh, const glm::dmat4& similarity) {
  transform_points(mesh.positions, similarity);
  const glm::dmat3 turn(similarity);
  for (std::size_t i = 0; i + 2 < mesh.normals.size(); i += 3) {
    const glm::dvec3 n = turn * glm::dvec3(mesh.normals[i], mesh.normals[i + 1], mesh.normals[i + 2]);
    const double length = glm::length(n);
    for (std::size_t a = 0; a < 3; ++a) mesh.normals[i + a] = length > 0 ? float(n[int(a)] / length) : 0.f;
  }
}

}  // namespace nf::geometry
