#pragma once
// CPU reference of the fur stage's three geometric strand losses (paper: Fur reconstruction), one
// template for float and double; the GPU kernels (shaders/fur/strand_bending*.comp,
// strand_losses_{fwd,bwd}.comp) are checked against it and it against finite differences.
//
// N strands of L points p_i^k. Segment directions b_i^l = d / sqrt(|d|^2 + delta_i^2),
// d = p_i^{l+1} - p_i^l, with delta_i = 1e-3 l_i / (L - 1) (l_i the strand's fur length): a
// zero-length segment stays finite at every scale.
//   growth direction  L_dir   = 1 / (N (L-1)) sum_i sum_l w^l max(0, -b_i^l . g_i),  w^l = l / (L-1)
//                     (l = 0 .. L-2: 0 at the root's segment, rising to the tip), g_i the knowledge's
//                     unit growth direction at the root;
//   curvature         L_shape = 1 / N sum_i 1 / (L-2) |theta_i - theta_mean|^2, theta_i^m the bending
//                     angle between segments m and m+1 (m = 0 .. L-3), theta_mean the batch's mean per
//                     m. The angle is atan2(sqrt(|u x v|^2 + eps^2), u . v) (eps = 1e-6): the paper's
//                     arccos(clamp(u . v)) without its infinite slope at straight strands. The batch
//                     mean's own derivative cancels (the deviations sum to zero), so each strand's
//                     adjoint is 2 (theta_i - theta_mean) / (N (L-2)) through its own angles;
//   penetration       L_pen   = 1 / (N L) sum_i sum_k max(0, -SDF(p_i^k)), SDF the bald body's grid
//                     (defur/sdf_file.hpp) interpolated trilinearly, clamped to the grid's box (outside
//                     it the value is the border's and the gradient 0).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace nf::fur {

inline constexpr double kSegmentGuardFraction = 1e-3;  // delta_i / (l_i / (L - 1))
inline constexpr double kBendGuard = 1e-6;             // eps of the bending angle

struct StrandLossShape {
  std::uint32_t strands = 0, points_per_strand = 100;
};

// The bald body's grid: sample (i, j, k) at origin + spacing (i, j, k), x fastest.
struct SdfGridRef {
  std::array<std::int32_t, 3> dims{0, 0, 0};
  std::array<double, 3> origin{0, 0, 0};
  double spacing = 1;
};

namespace detail {

template <class T>
struct V3 {
  T x, y, z;
  V3 operator+(const V3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  V3 operator-(const V3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  V3 operator*(T s) const { return {x * s, y * s, z * s}; }
  T dot(const V3& o) const { return x * o.x + y * o.y + z * o.z; }
  V3 cross(const V3& o) const { return {y * o.z - z * o.y, z * o.x - x * o.z, x * o.y - y * o.x}; }
};

template <class T>
V3<T> at(const std::vector<T>& v, std::size_t i) { return {v[3 * i], v[3 * i + 1], v[3 * i + 2]}; }

// Trilinear value and gradient of the grid at p (clamped; zero gradient along a clamped axis).
template <class T>
T sdf_sample(const SdfGridRef& g, const std::vector<T>& values, const V3<T>& p, V3<T>* gradient) {
  T q[3] = {(p.x - T(g.origin[0])) / T(g.spacing), (p.y - T(g.origin[1])) / T(g.spacing), (p.z - T(g.origin[2])) / T(g.spacing)};
  int i0[3];
  T f[3];
  bool inside[3];
  for (int a = 0; a < 3; ++a) {
    const T hi = T(g.dims[a] - 1);
    inside[a] = q[a] > T(0) && q[a] < hi;
    const T c = std::min(std::max(q[a], T(0)), hi);
    i0[a] = std::min(int(c), g.dims[a] - 2);
    f[a] = c - T(i0[a]);
  }
  const auto v = [&](int dx, int dy, int dz) {
    return values[(std::size_t(i0[2] + dz) * std::size_t(g.dims[1]) + std::size_t(i0[1] + dy)) * std::size_t(g.dims[0]) + std::size_t(i0[0] + dx)];
  };
  const T c00 = v(0, 0, 0) * (1 - f[0]) + v(1, 0, 0) * f[0], c10 = v(0, 1, 0) * (1 - f[0]) + v(1, 1, 0) * f[0];
  const T c01 = v(0, 0, 1) * (1 - f[0]) + v(1, 0, 1) * f[0], c11 = v(0, 1, 1) * (1 - f[0]) + v(1, 1, 1) * f[0];
  const T c0 = c00 * (1 - f[1]) + c10 * f[1], c1 = c01 * (1 - f[1]) + c11 * f[1];
  if (gradient) {
    const T gx = ((v(1, 0, 0) - v(0, 0, 0)) * (1 - f[1]) + (v(1, 1, 0) - v(0, 1, 0)) * f[1]) * (1 - f[2]) +
                 ((v(1, 0, 1) - v(0, 0, 1)) * (1 - f[1]) + (v(1, 1, 1) - v(0, 1, 1)) * f[1]) * f[2];
    const T gy = (c10 - c00) * (1 - f[2]) + (c11 - c01) * f[2];
    const T gz = c1 - c0;
    const T inv = T(1) / T(g.spacing);
    *gradient = {inside[0] ? gx * inv : T(0), inside[1] ? gy * inv : T(0), inside[2] ? gz * inv : T(0)};
  }
  return c0 * (1 - f[2]) + c1 * f[2];
}

// The guarded unit direction of d and, given dLoss/du, dLoss/dd.
template <class T>
V3<T> unit(const V3<T>& d, T delta2) { return d * (T(1) / std::sqrt(d.dot(d) + delta2)); }
template <class T>
V3<T> unit_adjoint(const V3<T>& d, T delta2, const V3<T>& grad_u) {
  const T n2 = d.dot(d) + delta2, n = std::sqrt(n2);
  return grad_u * (T(1) / n) - d * (d.dot(grad_u) / (n2 * n));
}

// Bending angle of unit-ish u, v and its derivatives.
template <class T>
T bend(const V3<T>& u, const V3<T>& v, V3<T>* du, V3<T>* dv) {
  const V3<T> w = u.cross(v);
  const T c = u.dot(v), s = std::sqrt(w.dot(w) + T(kBendGuard * kBendGuard));
  if (du) {
    const T r = s * s + c * c;
    const T dc = -s / r, ds = c / r;
    *du = v * dc + v.cross(w) * (ds / s);
    *dv = u * dc + w.cross(u) * (ds / s);
  }
  return std::atan2(s, c);
}

}  // namespace detail

// The three losses (unweighted) of a batch: {direction, curvature, penetration}.
template <class T>
std::array<T, 3> strand_losses_ref(const std::vector<T>& points, const std::vector<T>& guides, const std::vector<T>& lengths,
                                   const SdfGridRef& grid, const std::vector<T>& sdf, const StrandLossShape& shape) {
  using V = detail::V3<T>;
  const std::uint32_t N = shape.strands, L = shape.points_per_strand, S = L - 1, B = L - 2;
  std::array<T, 3> loss{0, 0, 0};
  std::vector<T> theta(std::size_t(N) * B), mean(B, T(0));
  for (std::uint32_t i = 0; i < N; ++i) {
    const T delta = T(kSegmentGuardFraction) * lengths[i] / T(S), delta2 = delta * delta;
    const V g = detail::at(guides, i);
    V prev{0, 0, 0};
    for (std::uint32_t l = 0; l < S; ++l) {
      const V b = detail::unit(detail::at(points, std::size_t(i) * L + l + 1) - detail::at(points, std::size_t(i) * L + l), delta2);
      loss[0] += T(l) / T(S) * std::max(T(0), -b.dot(g));
      if (l > 0) theta[std::size_t(i) * B + l - 1] = detail::bend<T>(prev, b, nullptr, nullptr);
      prev = b;
    }
    for (std::uint32_t k = 0; k < L; ++k) loss[2] += std::max(T(0), -detail::sdf_sample<T>(grid, sdf, detail::at(points, std::size_t(i) * L + k), nullptr));
  }
  for (std::uint32_t i = 0; i < N; ++i)
    for (std::uint32_t m = 0; m < B; ++m) mean[m] += theta[std::size_t(i) * B + m] / T(N);
  for (std::uint32_t i = 0; i < N; ++i)
    for (std::uint32_t m = 0; m < B; ++m) {
      const T e = theta[std::size_t(i) * B + m] - mean[m];
      loss[1] += e * e;
    }
  loss[0] /= T(N) * T(S);
  loss[1] /= T(N) * T(B);
  loss[2] /= T(N) * T(L);
  return loss;
}

// dLoss/dpoints for Loss = sum_t weights[t] * losses[t].
template <class T>
void strand_losses_backward_ref(const std::vector<T>& points, const std::vector<T>& guides, const std::vector<T>& lengths,
                                const SdfGridRef& grid, const std::vector<T>& sdf, const StrandLossShape& shape,
                                const std::array<T, 3>& weights, std::vector<T>& grad_points) {
  using V = detail::V3<T>;
  const std::uint32_t N = shape.strands, L = shape.points_per_strand, S = L - 1, B = L - 2;
  grad_points.assign(points.size(), T(0));
  std::vector<T> theta(std::size_t(N) * B), mean(B, T(0));
  std::vector<V> b(S), d(S);
  const auto directions = [&](std::uint32_t i, T delta2) {
    for (std::uint32_t l = 0; l < S; ++l) {
      d[l] = detail::at(points, std::size_t(i) * L + l + 1) - detail::at(points, std::size_t(i) * L + l);
      b[l] = detail::unit(d[l], delta2);
    }
  };
  for (std::uint32_t i = 0; i < N; ++i) {
    const T delta = T(kSegmentGuardFraction) * lengths[i] / T(S);
    directions(i, delta * delta);
    for (std::uint32_t m = 0; m < B; ++m) theta[std::size_t(i) * B + m] = detail::bend<T>(b[m], b[m + 1], nullptr, nullptr);
  }
  for (std::uint32_t i = 0; i < N; ++i)
    for (std::uint32_t m = 0; m < B; ++m) mean[m] += theta[std::size_t(i) * B + m] / T(N);
  std::vector<V> gb(S);
  for (std::uint32_t i = 0; i < N; ++i) {
    const T delta = T(kSegmentGuardFraction) * lengths[i] / T(S), delta2 = delta * delta;
    directions(i, delta2);
    const V g = detail::at(guides, i);
    for (std::uint32_t l = 0; l < S; ++l) gb[l] = (-b[l].dot(g) > T(0)) ? g * (-weights[0] * T(l) / T(S) / (T(N) * T(S))) : V{0, 0, 0};
    for (std::uint32_t m = 0; m < B; ++m) {
      V du, dv;
      detail::bend<T>(b[m], b[m + 1], &du, &dv);
      const T k = weights[1] * T(2) * (theta[std::size_t(i) * B + m] - mean[m]) / (T(N) * T(B));
      gb[m] = gb[m] + du * k;
      gb[m + 1] = gb[m + 1] + dv * k;
    }
    for (std::uint32_t l = 0; l < S; ++l) {
      const V gd = detail::unit_adjoint(d[l], delta2, gb[l]);
      T* p0 = &grad_points[(std::size_t(i) * L + l) * 3];
      p0[0] -= gd.x, p0[1] -= gd.y, p0[2] -= gd.z;
      p0[3] += gd.x, p0[4] += gd.y, p0[5] += gd.z;
    }
    for (std::uint32_t k = 0; k < L; ++k) {
      V grad;
      const T value = detail::sdf_sample<T>(grid, sdf, detail::at(points, std::size_t(i) * L + k), &grad);
      if (value < T(0)) {
        T* p = &grad_points[(std::size_t(i) * L + k) * 3];
        const T s = -weights[2] / (T(N) * T(L));
        p[0] += s * grad.x, p[1] += s * grad.y, p[2] += s * grad.z;
      }
    }
  }
}

}  // namespace nf::fur
