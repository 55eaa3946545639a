#pragma once
// The body fit's stage-3 regularisers with their gradients (the paper's, after WLDO): smoothness
// of the per-vertex displacement field (uniform Laplacian and edge differences) and normal
// consistency of the posed surface (1 - cos between faces that share an edge).
#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace nf::body {

struct MeshTopology {
  std::vector<std::array<std::uint32_t, 2>> edges;            // unique
  std::vector<std::vector<std::uint32_t>> neighbours;         // per vertex
  std::vector<std::array<std::uint32_t, 2>> face_pairs;       // faces sharing an edge
  MeshTopology(const std::vector<std::uint32_t>& triangles, std::size_t vertices);
};

// laplacian * mean_i |d_i - mean of its neighbours' d|^2 + edge * mean_edges |d_a - d_b|^2.
// Adds dL/dd to `grad`; returns L.
double displacement_smoothness(const MeshTopology& topology, const std::vector<glm::dvec3>& d, double laplacian,
                               double edge, std::vector<glm::dvec3>& grad);

// weight * mean over face pairs of (1 - n_a . n_b) of the surface at `positions`; adds dL/dp to
// `grad` (degenerate faces contribute nothing); returns L.
double normal_consistency(const MeshTopology& topology, const std::vector<std::uint32_t>& triangles,
                          const std::vector<glm::dvec3>& positions, double weight, std::vector<glm::dvec3>& grad);

}  // namespace nf::body
