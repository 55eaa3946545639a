#pragma once
// CPU reference of the strand geometry map of the fur stage (paper: Neural fur representation), one
// template for float and double: the GPU kernels (shaders/fur/strand_geometry_{fwd,bwd}.comp) are
// checked against it and it is checked against finite differences.
//
// Per strand s, the strand prior's decoder gives S segment vectors d_j (j = 0..S-1) in the root's
// frame (x along the tangent T, y along the bitangent B, z along the normal N). The strand's
// S + 1 points are
//     p'_k = sum_{j<k} d_j                       (p'_0 = 0: the root)
//     a    = sum_j sqrt(|d_j|^2 + delta^2)       (arc length, guarded)
//     p_k  = r + (l / a) (T p'_k.x + B p'_k.y + N p'_k.z)
// with r the root, l the region's fur length (scene units): a strand of arc length l whatever the
// decoder's scale. delta = 1e-6 (the decoder works at unit length, segments about 1e-2) keeps a
// decoder that outputs zeros (at initialisation, or a collapsed strand) finite: its points sit at the
// root with bounded gradients.
//
// Adjoint, with G_k = dLoss/dp_k and g'_k = (l / a) M^T G_k (M = [T B N]):
//     dLoss/dd_j = sum_{k>j} g'_k + (dLoss/da) d_j / sqrt(|d_j|^2 + delta^2),
//     dLoss/da   = -(l / a^2) sum_k (M^T G_k) . p'_k,
//     dLoss/dr = sum_k G_k,   dLoss/dl = (1 / a) sum_k (M^T G_k) . p'_k,
//     dLoss/dT = (l / a) sum_k p'_k.x G_k   (and B, N with y, z).
//
// Layouts: rows [strands][row_stride] (the decoder's output rows, segment j at 3j..3j+2; the
// padding after 3S is written 0 in the gradient); frames [strands][13]: r (3), l (1), T (3), B (3),
// N (3); points [strands][S + 1][3].
#include <cmath>
#include <cstdint>
#include <vector>

namespace nf::fur {

inline constexpr double kArcGuard = 1e-6;
inline constexpr std::uint32_t kFrameFloats = 13;

struct StrandGeometryShape {
  std::uint32_t strands = 0;
  std::uint32_t segments = 99;   // S: points per strand - 1
  std::uint32_t row_stride = 0;  // floats per decoder row, >= 3 S
  std::uint32_t points() const { return segments + 1; }
};

template <class T>
void strand_geometry_forward_ref(const std::vector<T>& rows, const std::vector<T>& frames, const StrandGeometryShape& shape,
                                 std::vector<T>& points) {
  const std::uint32_t S = shape.segments, P = S + 1;
  const T delta2 = T(kArcGuard * kArcGuard);
  points.assign(std::size_t(shape.strands) * P * 3, T(0));
  for (std::uint32_t s = 0; s < shape.strands; ++s) {
    const T* d = &rows[std::size_t(s) * shape.row_stride];
    const T* f = &frames[std::size_t(s) * kFrameFloats];
    T arc = 0;
    for (std::uint32_t j = 0; j < S; ++j) arc += std::sqrt(d[3 * j] * d[3 * j] + d[3 * j + 1] * d[3 * j + 1] + d[3 * j + 2] * d[3 * j + 2] + delta2);
    const T scale = f[3] / arc;
    T local[3] = {0, 0, 0};
    for (std::uint32_t k = 0; k < P; ++k) {
      if (k > 0)
        for (int c = 0; c < 3; ++c) local[c] += d[3 * (k - 1) + std::uint32_t(c)];
      T* p = &points[(std::size_t(s) * P + k) * 3];
      for (int c = 0; c < 3; ++c)
        p[c] = f[c] + scale * (f[4 + c] * local[0] + f[7 + c] * local[1] + f[10 + c] * local[2]);
    }
  }
}

// grad_rows: [strands][row_stride]; grad_frames: [strands][13].
template <class T>
void strand_geometry_backward_ref(const std::vector<T>& rows, const std::vector<T>& frames, const StrandGeometryShape& shape,
                                  const std::vector<T>& grad_points, std::vector<T>& grad_rows, std::vector<T>& grad_frames) {
  const std::uint32_t S = shape.segments, P = S + 1;
  const T delta2 = T(kArcGuard * kArcGuard);
  grad_rows.assign(rows.size(), T(0));
  grad_frames.assign(frames.size(), T(0));
  std::vector<T> g(std::size_t(P) * 3), local(std::size_t(P) * 3);
  for (std::uint32_t s = 0; s < shape.strands; ++s) {
    const T* d = &rows[std::size_t(s) * shape.row_stride];
    const T* f = &frames[std::size_t(s) * kFrameFloats];
    const T* G = &grad_points[std::size_t(s) * P * 3];
    T* gd = &grad_rows[std::size_t(s) * shape.row_stride];
    T* gf = &grad_frames[std::size_t(s) * kFrameFloats];
    T arc = 0;
    for (std::uint32_t j = 0; j < S; ++j) arc += std::sqrt(d[3 * j] * d[3 * j] + d[3 * j + 1] * d[3 * j + 1] + d[3 * j + 2] * d[3 * j + 2] + delta2);
    const T scale = f[3] / arc;
    T dot = 0;  // sum_k (M^T G_k) . p'_k: l = 0 stays finite
    for (std::uint32_t k = 0; k < P; ++k) {
      for (int c = 0; c < 3; ++c) local[3 * k + std::uint32_t(c)] = k == 0 ? T(0) : local[3 * (k - 1) + std::uint32_t(c)] + d[3 * (k - 1) + std::uint32_t(c)];
      const T* Gk = &G[3 * k];
      for (int c = 0; c < 3; ++c) {  // h_k = M^T G_k; g'_k = scale h_k
        const T* axis = &f[4 + 3 * c];
        const T h = axis[0] * Gk[0] + axis[1] * Gk[1] + axis[2] * Gk[2];
        g[3 * k + std::uint32_t(c)] = scale * h;
        dot += h * local[3 * k + std::uint32_t(c)];
      }
      for (int c = 0; c < 3; ++c) {
        gf[c] += Gk[c];  // root
        for (int a = 0; a < 3; ++a) gf[4 + 3 * a + c] += scale * local[3 * k + std::uint32_t(a)] * Gk[c];  // T, B, N
      }
    }
    gf[3] = dot / arc;
    const T grad_arc = -scale * dot / arc;
    T suffix[3] = {0, 0, 0};
    for (std::uint32_t j = S; j-- > 0;) {
      for (int c = 0; c < 3; ++c) suffix[c] += g[3 * (j + 1) + std::uint32_t(c)];
      const T norm = std::sqrt(d[3 * j] * d[3 * j] + d[3 * j + 1] * d[3 * j + 1] + d[3 * j + 2] * d[3 * j + 2] + delta2);
      for (int c = 0; c < 3; ++c) gd[3 * j + std::uint32_t(c)] = suffix[c] + grad_arc * d[3 * j + std::uint32_t(c)] / norm;
    }
  }
}

}  // namespace nf::fur
