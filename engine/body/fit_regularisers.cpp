#include "engine/body/fit_regularisers.hpp"

#include <algorithm>
#include <map>

namespace nf::body {

MeshTopology::MeshTopology(const std::vector<std::uint32_t>& triangles, std::size_t vertices) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> first_face;
  neighbours.resize(vertices);
  for (std::uint32_t f = 0; std::size_t(f) * 3 < triangles.size(); ++f)
    for (int e = 0; e < 3; ++e) {
      std::uint32_t a = triangles[3 * f + std::size_t(e)], b = triangles[3 * f + std::size_t(e + 1) % 3];
      if (a > b) std::swap(a, b);
      const auto [it, fresh] = first_face.emplace(std::make_pair(a, b), f);
      if (fresh) {
        edges.push_back({a, b});
        neighbours[a].push_back(b), neighbours[b].push_back(a);
      } else {
        face_pairs.push_back({it->second, f});
      }
    }
}

double displacement_smoothness(const MeshTopology& t, const std::vector<glm::dvec3>& d, double laplacian, double edge,
                               std::vector<glm::dvec3>& grad) {
  const std::size_t V = d.size();
  double loss = 0;
  std::vector<glm::dvec3> u(V, glm::dvec3(0.0));  // d_i - mean of the neighbours
  for (std::size_t i = 0; i < V; ++i) {
    const auto& nb = t.neighbours[i];
    if (nb.empty()) continue;
    glm::dvec3 mean(0.0);
    for (std::uint32_t j : nb) mean += d[j];
    u[i] = d[i] - mean / double(nb.size());
    loss += laplacian * glm::dot(u[i], u[i]) / double(V);
  }
  for (std::size_t i = 0; i < V; ++i) {
    const auto& nb = t.neighbours[i];
    if (nb.empty()) continue;
    const glm::dvec3 g = 2.0 * laplacian * u[i] / double(V);
    grad[i] += g;
    for (std::uint32_t j : nb) grad[j] -= g / double(nb.size());
  }
  const double E = double(std::max<std::size_t>(1, t.edges.size()));
  for (const auto& e : t.edges) {
    const glm::dvec3 diff = d[e[0]] - d[e[1]];
    loss += edge * glm::dot(diff, diff) / E;
    grad[e[0]] += 2.0 * edge * diff / E, grad[e[1]] -= 2.0 * edge * diff / E;
  }
  return loss;
}

double normal_consistency(const MeshTopology& t, const std::vector<std::uint32_t>& triangles,
                          const std::vector<glm::dvec3>& p, double weight, std::vector<glm::dvec3>& grad) {
  const std::size_t F = triangles.size() / 3;
  std::vector<glm::dvec3> cross(F), normal(F);
  for (std::size_t f = 0; f < F; ++f) {
    const glm::dvec3 a = p[triangles[3 * f]], b = p[triangles[3 * f + 1]], c = p[triangles[3 * f + 2]];
    cross[f] = glm::cross(b - a, c - a);
    const double len = glm::length(cross[f]);
    normal[f] = len > 1e-20 ? cross[f] / len : glm::dvec3(0.0);
  }
  double loss = 0;
  std::vector<glm::dvec3> d_normal(F, glm::dvec3(0.0));
  const double P = double(std::max<std::size_t>(1, t.face_pairs.size()));
  for (const auto& pair : t.face_pairs) {
    loss += weight * (1.0 - glm::dot(normal[pair[0]], normal[pair[1]])) / P;
    d_normal[pair[0]] -= weight * normal[pair[1]] / P;
    d_normal[pair[1]] -= weight * normal[pair[0]] / P;
  }
  for (std::size_t f = 0; f < F; ++f) {
    const double len = glm::length(cross[f]);
    if (len <= 1e-20) continue;
    // n = c / |c|: dL/dc = (I - n n^T) dL/dn / |c|; c = e1 x e2.
    const glm::dvec3 n = normal[f], g = (d_normal[f] - glm::dot(d_normal[f], n) * n) / len;
    const std::uint32_t ia = triangles[3 * f], ib = triangles[3 * f + 1], ic = triangles[3 * f + 2];
    const glm::dvec3 e1 = p[ib] - p[ia], e2 = p[ic] - p[ia];
    const glm::dvec3 de1 = glm::cross(e2, g), de2 = glm::cross(g, e1);
    grad[ia] -= de1 + de2, grad[ib] += de1, grad[ic] += de2;
  }
  return loss;
}

}  // namespace nf::body
