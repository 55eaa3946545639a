#pragma once
// CPU reference of the fur stage's one-way chamfer (paper: Chamfer loss): K points x_k sampled on
// M_NeuS each pulled towards its nearest strand point,
//     L_chm = 1/K sum_k |x_k - p_nn(k)|^2,   dL/dp_j = 2/K sum_{k: nn(k) = j} (p_j - x_k),
// nn(k) the nearest strand point (ties to the lowest index). A query farther than `reach` from every
// strand point is unmatched: it adds nothing (its term is 0, K still counts it). Brute force here;
// the GPU version (strand_chamfer.hpp) searches a uniform grid of cells, reach = max_rings x cell,
// and must pick the same points.
#include <cstdint>
#include <limits>
#include <vector>

namespace nf::fur {

inline constexpr std::uint32_t kUnmatched = 0xffffffffu;

template <class T>
std::vector<std::uint32_t> nearest_points_ref(const std::vector<T>& queries, const std::vector<T>& points, double reach) {
  const std::size_t K = queries.size() / 3, M = points.size() / 3;
  std::vector<std::uint32_t> nn(K, 0);
  for (std::size_t k = 0; k < K; ++k) {
    T best = std::numeric_limits<T>::infinity();
    for (std::size_t j = 0; j < M; ++j) {
      T d2 = 0;
      for (int c = 0; c < 3; ++c) d2 += (queries[3 * k + std::size_t(c)] - points[3 * j + std::size_t(c)]) * (queries[3 * k + std::size_t(c)] - points[3 * j + std::size_t(c)]);
      if (d2 < best) best = d2, nn[k] = std::uint32_t(j);
    }
    if (!(best <= T(reach) * T(reach))) nn[k] = kUnmatched;
  }
  return nn;
}

template <class T>
T strand_chamfer_ref(const std::vector<T>& queries, const std::vector<T>& points, double reach) {
  const std::vector<std::uint32_t> nn = nearest_points_ref(queries, points, reach);
  T sum = 0;
  for (std::size_t k = 0; k < nn.size(); ++k)
    for (int c = 0; c < 3 && nn[k] != kUnmatched; ++c) {
      const T d = queries[3 * k + std::size_t(c)] - points[3 * std::size_t(nn[k]) + std::size_t(c)];
      sum += d * d;
    }
  return nn.empty() ? T(0) : sum / T(nn.size());
}

// dLoss/dpoints for Loss = weight * L_chm.
template <class T>
std::vector<T> strand_chamfer_backward_ref(const std::vector<T>& queries, const std::vector<T>& points, double reach, T weight) {
  const std::vector<std::uint32_t> nn = nearest_points_ref(queries, points, reach);
  std::vector<T> grad(points.size(), T(0));
  for (std::size_t k = 0; k < nn.size(); ++k)
    for (int c = 0; c < 3 && nn[k] != kUnmatched; ++c)
      grad[3 * std::size_t(nn[k]) + std::size_t(c)] += weight * T(2) / T(nn.size()) * (points[3 * std::size_t(nn[k]) + std::size_t(c)] - queries[3 * k + std::size_t(c)]);
  return grad;
}

}  // namespace nf::fur
