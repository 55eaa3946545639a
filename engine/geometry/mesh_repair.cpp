#include "engine/geometry/mesh_repair.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <unordered_map>

#include <glm/glm.hpp>
#include <meshoptimizer.h>

#include "engine/geometry/mesh_tools.hpp"

namespace nf::geometry {
namespace {

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return a < b ? (std::uint64_t(a) << 32) | b : (std::uint64_t(b) << 32) | a;
}

// Keeps the faces with keep[f] != 0.
void keep_faces(Mesh& mesh, const std::vector<std::uint8_t>& keep) {
  std::size_t out = 0;
  for (std::size_t f = 0; f < keep.size(); ++f)
    if (keep[f])
      for (int k = 0; k < 3; ++k) mesh.triangles[out++] = mesh.triangles[3 * f + std::size_t(k)];
  mesh.triangles.resize(out);
}

// Drops vertices no face uses; regions and normals follow.
void drop_unused_vertices(Mesh& mesh) {
  const std::size_t nv = mesh.vertex_count();
  std::vector<std::uint32_t> remap(nv, ~0u);
  for (std::uint32_t v : mesh.triangles) remap[v] = 0;
  const bool normals = mesh.normals.size() == mesh.positions.size(), regions = mesh.regions.size() == nv;
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (remap[v] != 0) continue;
    for (int c = 0; c < 3; ++c) {
      mesh.positions[3 * next + std::uint32_t(c)] = mesh.positions[3 * v + std::size_t(c)];
      if (normals) mesh.normals[3 * next + std::uint32_t(c)] = mesh.normals[3 * v + std::size_t(c)];
    }
    if (regions) mesh.regions[next] = mesh.regions[v];
    remap[v] = next++;
  }
  mesh.positions.resize(3 * std::size_t(next));
  if (normals) mesh.normals.resize(3 * std::size_t(next));
  if (regions) mesh.regions.resize(next);
  for (std::uint32_t& v : mesh.triangles) v = remap[v];
}

}  // namespace

json to_json(const RepairReport& r) {
  return {{"degenerate_faces", r.degenerate_faces}, {"duplicate_faces", r.duplicate_faces},
          {"non_manifold_faces", r.non_manifold_faces}, {"holes_filled", r.holes_filled},
          {"holes_left", r.holes_left}, {"components_dropped", r.components_dropped}};
}

RepairReport repair_mesh(Mesh& mesh, std::uint32_t max_hole_edges) {
  RepairReport report;
  const bool had_normals = !mesh.normals.empty();
  std::size_t nf = mesh.triangle_count();
  // Degenerate faces.
  std::vector<std::uint8_t> keep(nf, 1);
  for (std::size_t f = 0; f < nf; ++f) {
    const std::uint32_t a = mesh.triangles[3 * f], b = mesh.triangles[3 * f + 1], c = mesh.triangles[3 * f + 2];
    const bool degenerate = a == b || b == c || a == c ||
                            glm::length(glm::cross(mesh.position(b) - mesh.position(a), mesh.position(c) - mesh.position(a))) == 0;
    if (degenerate) keep[f] = 0, ++report.degenerate_faces;
  }
  // Duplicates (any order or winding of the same three vertices).
  std::vector<std::pair<std::array<std::uint32_t, 3>, std::uint32_t>> sorted;
  sorted.reserve(nf);
  for (std::size_t f = 0; f < nf; ++f)
    if (keep[f]) {
      std::array<std::uint32_t, 3> t{mesh.triangles[3 * f], mesh.triangles[3 * f + 1], mesh.triangles[3 * f + 2]};
      std::sort(t.begin(), t.end());
      sorted.push_back({t, std::uint32_t(f)});
    }
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 1; i < sorted.size(); ++i)
    if (sorted[i].first == sorted[i - 1].first) keep[sorted[i].second] = 0, ++report.duplicate_faces;
  keep_faces(mesh, keep);
  // Faces on edges used more than twice.
  nf = mesh.triangle_count();
  std::unordered_map<std::uint64_t, std::uint32_t> uses;
  uses.reserve(3 * nf);
  for (std::size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++uses[edge_key(mesh.triangles[3 * f + std::size_t(k)], mesh.triangles[3 * f + std::size_t(k + 1) % 3])];
  keep.assign(nf, 1);
  for (std::size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k)
      if (uses[edge_key(mesh.triangles[3 * f + std::size_t(k)], mesh.triangles[3 * f + std::size_t(k + 1) % 3])] > 2) keep[f] = 0;
  for (std::uint8_t k : keep) report.non_manifold_faces += k == 0;
  if (report.non_manifold_faces) {
    keep_faces(mesh, keep);
    nf = mesh.triangle_count();
    uses.clear();
    for (std::size_t f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) ++uses[edge_key(mesh.triangles[3 * f + std::size_t(k)], mesh.triangles[3 * f + std::size_t(k + 1) % 3])];
  }
  // Holes: loops of boundary half-edges (a -> b of a face whose edge no other face uses).
  std::multimap<std::uint32_t, std::uint32_t> boundary;  // a -> b
  for (std::size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.triangles[3 * f + std::size_t(k)], b = mesh.triangles[3 * f + std::size_t(k + 1) % 3];
      if (uses[edge_key(a, b)] == 1) boundary.emplace(a, b);
    }
  while (!boundary.empty()) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> loop;
    auto it = boundary.begin();
    const std::uint32_t start = it->first;
    bool closed = false, pinched = false;
    std::set<std::uint32_t> seen{start};
    while (it != boundary.end()) {
      loop.push_back(*it);
      const std::uint32_t next = it->second;
      boundary.erase(it);
      if (next == start) {
        closed = true;
        break;
      }
      // Through a vertex two holes share: a fan over both would reuse edges; leave it open.
      if (!seen.insert(next).second) pinched = true;
      it = boundary.find(next);
    }
    if (!closed || pinched || loop.size() > max_hole_edges || loop.size() < 3) {
      ++report.holes_left;
      continue;
    }
    glm::vec3 centre(0.f);
    std::map<std::int32_t, int> votes;
    for (const auto& [a, b] : loop) {
      centre += mesh.position(a);
      if (!mesh.regions.empty()) ++votes[mesh.regions[a]];
    }
    centre /= float(loop.size());
    const std::uint32_t c = std::uint32_t(mesh.vertex_count());
    mesh.positions.insert(mesh.positions.end(), {centre.x, centre.y, centre.z});
    if (!mesh.normals.empty()) mesh.normals.insert(mesh.normals.end(), {0.f, 0.f, 0.f});
    if (!mesh.regions.empty())
      mesh.regions.push_back(std::max_element(votes.begin(), votes.end(), [](auto& x, auto& y) { return x.second < y.second; })->first);
    for (const auto& [a, b] : loop) mesh.triangles.insert(mesh.triangles.end(), {b, a, c});
    ++report.holes_filled;
  }
  const std::size_t components = keep_largest_component(mesh);
  report.components_dropped = components > 0 ? components - 1 : 0;
  drop_unused_vertices(mesh);
  if (had_normals) compute_vertex_normals(mesh);
  return report;
}

DecimateReport decimate(Mesh& mesh, std::uint64_t target_faces) {
  DecimateReport report;
  report.faces_before = report.faces_after = mesh.triangle_count();
  if (mesh.triangle_count() <= target_faces || mesh.vertex_count() == 0) return report;
  std::vector<std::uint32_t> out(mesh.triangles.size());
  float error = 0;
  // The error bound is loose on purpose: the face budget decides; the achieved error is reported.
  const std::size_t n = meshopt_simplify(out.data(), mesh.triangles.data(), mesh.triangles.size(), mesh.positions.data(),
                                         mesh.vertex_count(), 3 * sizeof(float), 3 * target_faces, 0.05f, 0, &error);
  out.resize(n);
  const float scale = meshopt_simplifyScale(mesh.positions.data(), mesh.vertex_count(), 3 * sizeof(float));
  mesh.triangles = std::move(out);
  const bool had_normals = !mesh.normals.empty();
  drop_unused_vertices(mesh);
  if (had_normals) compute_vertex_normals(mesh);
  report.faces_after = mesh.triangle_count();
  report.error = double(error) * double(scale);
  return report;
}

}  // namespace nf::geometry
