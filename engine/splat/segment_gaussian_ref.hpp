#pragma once
// CPU reference of the segment-to-Gaussian map of strand splatting (paper, supplementary
// "Gaussian Splatting"), one template for float and double: the GPU kernels are checked against it
// and it is checked against finite differences.
//
// Segment l of strand i runs from p_l to p_{l+1}; d = p_{l+1} - p_l. Its Gaussian has
//   mean       mu = (p_l + p_{l+1}) / 2
//   covariance C  = E D (E D)^T,  E = {b, t, n} orthonormal with b = d/|d|,  D = diag(f, eps, eps)
// with f = k |d| (k = length_scale) and eps the strand width. Because E is orthonormal,
//   C = f^2 b b^T + eps^2 (I - b b^T) = eps^2 I + (k^2 - eps^2/|d|^2) d d^T,
// independent of how t and n are chosen. The 1/|d|^2 is guarded as 1/(|d|^2 + delta^2) with
// delta = 1e-3 eps: exact to a relative 1e-6 once |d| > eps, smooth through |d| = 0 (a zero-length
// segment becomes an isotropic Gaussian of radius eps) with bounded gradients.
//
// Covariances are stored as 6 floats per segment: xx, xy, xz, yy, yz, zz. The adjoint treats each
// stored off-diagonal as one variable (it stands for C_xy and C_yx together).
#include <cstdint>
#include <vector>

namespace nf::splat {

struct SegmentGaussianParams {
  double length_scale = 0.5;  // k: sigma along the segment as a fraction of its length
  double width = 0.0025;      // eps: sigma across the strand, scene units
};

constexpr double kSegmentGuard = 1e-3;  // delta / eps

template <class T>
struct SegmentGaussianTerms {
  T k2, eps2, delta2;
  explicit SegmentGaussianTerms(const SegmentGaussianParams& p)
      : k2(T(p.length_scale * p.length_scale)), eps2(T(p.width * p.width)),
        delta2(T(kSegmentGuard * kSegmentGuard * p.width * p.width)) {}
};

// points: strands * points_per_strand * 3. means: segments * 3, covariances: segments * 6.
template <class T>
void segment_gaussian_forward_ref(const std::vector<T>& points, std::uint32_t strands, std::uint32_t points_per_strand,
                                  const SegmentGaussianParams& params, std::vector<T>& means,
                                  std::vector<T>& covariances) {
  const SegmentGaussianTerms<T> c(params);
  const std::uint32_t segs = points_per_strand - 1;
  means.assign(std::size_t(strands) * segs * 3, T(0));
  covariances.assign(std::size_t(strands) * segs * 6, T(0));
  for (std::uint32_t s = 0; s < strands; ++s) {
    for (std::uint32_t l = 0; l < segs; ++l) {
      const T* p0 = &points[(std::size_t(s) * points_per_strand + l) * 3];
      const T* p1 = p0 + 3;
      const std::size_t g = std::size_t(s) * segs + l;
      const T d[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
      const T len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
      const T a = c.k2 - c.eps2 / (len2 + c.delta2);
      for (int j = 0; j < 3; ++j) means[g * 3 + j] = T(0.5) * (p0[j] + p1[j]);
      T* cov = &covariances[g * 6];
      cov[0] = c.eps2 + a * d[0] * d[0];
      cov[1] = a * d[0] * d[1];
      cov[2] = a * d[0] * d[2];
      cov[3] = c.eps2 + a * d[1] * d[1];
      cov[4] = a * d[1] * d[2];
      cov[5] = c.eps2 + a * d[2] * d[2];
    }
  }
}

// dL/dd of one segment from dL/dC (stored form), written to grad_d.
template <class T>
void segment_covariance_adjoint(const T d[3], const T g[6], const SegmentGaussianTerms<T>& c, T grad_d[3]) {
  const T len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  const T s = len2 + c.delta2;
  const T a = c.k2 - c.eps2 / s;
  // H: symmetric matrix with the stored off-diagonal gradients split over both entries.
  const T hd[3] = {g[0] * d[0] + T(0.5) * (g[1] * d[1] + g[2] * d[2]),
                   g[3] * d[1] + T(0.5) * (g[1] * d[0] + g[4] * d[2]),
                   g[5] * d[2] + T(0.5) * (g[2] * d[0] + g[4] * d[1])};
  const T dhd = d[0] * hd[0] + d[1] * hd[1] + d[2] * hd[2];
  // d/dd [a(d) d^T H d] = 2 a H d + (d^T H d) * 2 eps^2 d / s^2, grouped to keep magnitudes moderate.
  const T radial = T(2) * (c.eps2 / s) * (dhd / s);
  for (int j = 0; j < 3; ++j) grad_d[j] = T(2) * a * hd[j] + radial * d[j];
}

// grad_points = dL/dpoints given dL/dmeans and dL/dcovariances.
template <class T>
void segment_gaussian_backward_ref(const std::vector<T>& points, std::uint32_t strands,
                                   std::uint32_t points_per_strand, const SegmentGaussianParams& params,
                                   const std::vector<T>& grad_means, const std::vector<T>& grad_covariances,
                                   std::vector<T>& grad_points) {
  const SegmentGaussianTerms<T> c(params);
  const std::uint32_t segs = points_per_strand - 1;
  grad_points.assign(points.size(), T(0));
  for (std::uint32_t s = 0; s < strands; ++s) {
    for (std::uint32_t l = 0; l < segs; ++l) {
      const std::size_t i0 = (std::size_t(s) * points_per_strand + l) * 3, i1 = i0 + 3;
      const std::size_t g = std::size_t(s) * segs + l;
      const T d[3] = {points[i1] - points[i0], points[i1 + 1] - points[i0 + 1], points[i1 + 2] - points[i0 + 2]};
      T grad_d[3];
      segment_covariance_adjoint(d, &grad_covariances[g * 6], c, grad_d);
      for (int j = 0; j < 3; ++j) {
        const T half_mean = T(0.5) * grad_means[g * 3 + j];
        grad_points[i0 + j] += half_mean - grad_d[j];
        grad_points[i1 + j] += half_mean + grad_d[j];
      }
    }
  }
}

}  // namespace nf::splat
