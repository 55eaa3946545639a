#pragma once
// CPU reference of differentiable strand rasterisation (one template for float and double): the
// GPU kernels (shaders/splat/rasterize_*.comp, engine/splat/rasterizer.cpp) are checked against
// it, and it is checked against finite differences.
//
// Per segment l of strand s (points p0 = p_l, p1 = p_{l+1}), in camera space (OpenGL: looks down
// -z; depth z = -z_cam):
//   mean  m = R (p0 + p1)/2 + t,   d = R (p1 - p0),   covariance M = eps^2 I + a d d^T,
//   a = k^2 - eps^2 / (|d|^2 + delta^2)                       (segment_gaussian_ref.hpp)
//   pixel mean   u = cx + fx m.x / z,  v = cy - fy m.y / z     (Camera::project's convention)
//   Jacobian     J = [[fx/z, 0, fx tx/z], [0, -fy/z, -fy ty/z]], tx = clamp(m.x/z, +-lim_x) (no
//                gradient through tx, ty where the clamp is active; lim = 1.3 x the half field of view)
//   2D covariance S = J M J^T + 0.3 I (low-pass), conic = S^-1 stored (a, b, c) for a x^2 + 2bxy + cy^2
//   opacity      o = sqrt(max(det(J M J^T) / det(S), 2.5e-5))   (anti-aliasing compensation of
//                sub-pixel strands, floored; no gradient under the floor)
//   orientation  w = J d (the projected segment, pixels; v down), (cos 2b, sin 2b) with b measured
//                counter-clockwise on screen from +x: w' = (w.x, -w.y),
//                o2 = (w'x^2 - w'y^2, 2 w'x w'y) / (|w|^2 + gamma), gamma = 1e-4 px^2 (edge-on
//                segments fade to no orientation instead of dividing by zero)
//   culled when z < near or z > far, or the 3.5-sigma rectangle misses the image.
// Tiles of 8 x 8 pixels (shaders/include/nf_splat_tile.glsl says why); a Gaussian is considered for the pixels of the tiles its rectangle
// touches, front to back by (depth quantised to `depth_bits` bits between near and far, index).
// Per pixel centre q = (x + 0.5, y + 0.5): r_i = min(0.99, o_i exp(-0.5 (q-u)^T conic (q-u))),
// skipped when r_i < 1/255 or when the Gaussian lies behind the body (depth > body depth at the
// pixel), else alpha_i = (r_i - 1/255) / (1 - 1/255): the cut-off is continuous (3DGS's jumps by
// 1/255, which makes finite differences of any realistic scene cross a jump somewhere); w_i = alpha_i T_i, T_{i+1} = T_i (1 - alpha_i), stopping before T would drop below
// 1e-4. Channels: alpha = 1 - T_end, orientation = sum w_i o2_i (2 channels), confidence =
// sum w_i conf_i (the per-segment attribute), depth = sum w_i z_i. The clamp at 0.99 has zero
// gradient; the backward divides by max(1e-6, 1 - alpha_i).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "engine/splat/segment_gaussian_ref.hpp"

namespace nf::splat {

inline constexpr std::uint32_t kTile = 8;  // twin of NF_TILE
inline constexpr int kChannels = 5;  // alpha, orientation x, orientation y, confidence, depth
inline constexpr int kProjected = 12;  // floats per projected Gaussian (see ProjectedLayout)

// Layout of one projected Gaussian.
enum ProjectedLayout : int { kU, kV, kConicA, kConicB, kConicC, kOpacity, kDepth, kOrientX, kOrientY, kConf, kRadius, kValid };

struct RasterCamera {
  double world_to_camera[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};  // rows of [R | t]
  double fx = 100, fy = 100, cx = 50, cy = 50;
  std::uint32_t width = 100, height = 100;
  double near = 0.01, far = 100;
};

struct RasterParams {
  SegmentGaussianParams gaussian;
  double low_pass = 0.3;            // px^2 added to the 2D covariance
  double orientation_guard = 1e-4;  // gamma, px^2
  // Tile-list entries one compositing pass walks (0: the device's choice, the whole list where
  // loops have no iteration limit). Execution only: the image and gradients do not depend on it.
  std::uint32_t walk_chunk = 0;
};

inline std::uint32_t tiles_x(const RasterCamera& c) { return (c.width + kTile - 1) / kTile; }
inline std::uint32_t tiles_y(const RasterCamera& c) { return (c.height + kTile - 1) / kTile; }
// Bits of a tile index. Depth is quantised to the remaining 32 - tile_bits bits: the layout of an
// earlier combined (tile, depth) sort key, kept because it fixes which near-equal depths tie (ties
// keep index order), and the GPU sorts (depth, then tile) must tie the same way.
inline std::uint32_t tile_bits(const RasterCamera& c) {
  std::uint32_t bits = 1, tiles = tiles_x(c) * tiles_y(c);
  while ((1u << bits) < tiles) ++bits;
  return bits;
}
inline std::uint32_t depth_bits(const RasterCamera& c) { return 32 - tile_bits(c); }

template <class T>
std::uint32_t quantise_depth(T z, const RasterCamera& c) {
  const double top = double((1ull << depth_bits(c)) - 1);
  const double f = std::clamp((double(z) - c.near) / (c.far - c.near), 0.0, 1.0);
  return std::uint32_t(f * top);
}

template <class T>
struct Vec3T {
  T x, y, z;
};

// Everything the projection of one segment computes before its outputs, shared by the forward and
// the adjoint so both see the same numbers.
template <class T>
struct SegmentProjection {
  T m[3], d[3], z;          // camera-space mean and segment vector, depth
  T fx, fy, tx, ty;         // focal lengths; clamped m.x/z, m.y/z
  bool free_x, free_y;      // the clamp is inactive (the gradient flows)
  T J[2][3];                // projection Jacobian at the mean
  T s, a;                   // |d|^2 + delta^2; the covariance's d d^T coefficient
  T w[2];                   // J d, the projected segment (pixels)
  T s00, s01, s11;          // J M J^T
  T A, B, C, D, D0;         // S = J M J^T + low-pass, det S, det(J M J^T)

  SegmentProjection(const T* p0, const T* p1, const RasterCamera& cam, const RasterParams& rp) {
    const SegmentGaussianTerms<T> g(rp.gaussian);
    T W[12];
    for (int i = 0; i < 12; ++i) W[i] = T(cam.world_to_camera[i]);
    const T mu[3] = {T(0.5) * (p0[0] + p1[0]), T(0.5) * (p0[1] + p1[1]), T(0.5) * (p0[2] + p1[2])};
    const T dw[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    for (int r = 0; r < 3; ++r) {
      m[r] = W[4 * r] * mu[0] + W[4 * r + 1] * mu[1] + W[4 * r + 2] * mu[2] + W[4 * r + 3];
      d[r] = W[4 * r] * dw[0] + W[4 * r + 1] * dw[1] + W[4 * r + 2] * dw[2];
    }
    z = -m[2];
    fx = T(cam.fx), fy = T(cam.fy);
    const T lim_x = T(1.3) * T(std::max(cam.cx, cam.width - cam.cx) / cam.fx);
    const T lim_y = T(1.3) * T(std::max(cam.cy, cam.height - cam.cy) / cam.fy);
    const T rx = m[0] / z, ry = m[1] / z;
    free_x = rx > -lim_x && rx < lim_x, free_y = ry > -lim_y && ry < lim_y;
    tx = std::clamp(rx, -lim_x, lim_x), ty = std::clamp(ry, -lim_y, lim_y);
    J[0][0] = fx / z, J[0][1] = T(0), J[0][2] = fx * tx / z;
    J[1][0] = T(0), J[1][1] = -fy / z, J[1][2] = -fy * ty / z;
    s = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + g.delta2;
    a = g.k2 - g.eps2 / s;
    // J M J^T = eps^2 J J^T + a (J d)(J d)^T.
    w[0] = J[0][0] * d[0] + J[0][2] * d[2], w[1] = J[1][1] * d[1] + J[1][2] * d[2];
    const T jj00 = J[0][0] * J[0][0] + J[0][2] * J[0][2], jj01 = J[0][2] * J[1][2], jj11 = J[1][1] * J[1][1] + J[1][2] * J[1][2];
    s00 = g.eps2 * jj00 + a * w[0] * w[0], s01 = g.eps2 * jj01 + a * w[0] * w[1], s11 = g.eps2 * jj11 + a * w[1] * w[1];
    const T lp = T(rp.low_pass);
    A = s00 + lp, B = s01, C = s11 + lp;
    D = A * C - B * B, D0 = s00 * s11 - s01 * s01;
  }
};

// Forward projection of one segment into kProjected floats; returns false when culled.
template <class T>
bool project_segment(const T* p0, const T* p1, T conf, const RasterCamera& cam, const RasterParams& rp, T* out) {
  std::fill(out, out + kProjected, T(0));
  const SegmentProjection<T> q(p0, p1, cam, rp);
  if (!(q.z >= T(cam.near)) || !(q.z <= T(cam.far))) return false;
  if (!(q.D > T(0))) return false;
  const T opacity = std::sqrt(std::max(q.D0 / q.D, T(2.5e-5)));
  const T mid = T(0.5) * (q.A + q.C);
  const T lambda = mid + std::sqrt(std::max(T(0.1), mid * mid - q.D));
  const T radius = std::ceil(T(3.5) * std::sqrt(lambda));
  const T u = T(cam.cx) + q.fx * q.m[0] / q.z, v = T(cam.cy) - q.fy * q.m[1] / q.z;
  if (u + radius <= T(0) || v + radius <= T(0) || u - radius >= T(cam.width) || v - radius >= T(cam.height)) return false;
  const T n = q.w[0] * q.w[0] + q.w[1] * q.w[1] + T(rp.orientation_guard);
  out[kU] = u, out[kV] = v;
  out[kConicA] = q.C / q.D, out[kConicB] = -q.B / q.D, out[kConicC] = q.A / q.D;
  out[kOpacity] = opacity, out[kDepth] = q.z;
  out[kOrientX] = (q.w[0] * q.w[0] - q.w[1] * q.w[1]) / n;
  out[kOrientY] = T(-2) * q.w[0] * q.w[1] / n;  // screen y is up for the angle: w' = (w.x, -w.y)
  out[kConf] = conf, out[kRadius] = radius, out[kValid] = T(1);
  return true;
}

// Adjoint of project_segment: g (kProjected floats; the radius and valid entries are ignored) ->
// gradients of p0, p1 (added) and conf (returned). Culled segments get nothing.
template <class T>
T project_segment_adjoint(const T* p0, const T* p1, const RasterCamera& cam, const RasterParams& rp, const T* g,
                          T* g_p0, T* g_p1) {
  T fwd[kProjected];
  if (!project_segment(p0, p1, T(0), cam, rp, fwd)) return T(0);
  const SegmentGaussianTerms<T> gt(rp.gaussian);
  const SegmentProjection<T> q(p0, p1, cam, rp);
  const auto& [m, d, z, fx, fy, tx, ty, free_x, free_y, J, s, a, w, s00, s01, s11, A, B, C, D, D0] = q;
  T W[12];
  for (int i = 0; i < 12; ++i) W[i] = T(cam.world_to_camera[i]);

  // Conic (C/D, -B/D, A/D) and opacity sqrt(D0/D) -> dL/d(A, B, C) and dL/d(s00, s01, s11).
  const T D2 = D * D;
  T gA = g[kConicA] * (-C * C / D2) + g[kConicB] * (B * C / D2) + g[kConicC] * (-B * B / D2);
  T gB = g[kConicA] * (T(2) * B * C / D2) + g[kConicB] * (T(-1) / D - T(2) * B * B / D2) + g[kConicC] * (T(2) * A * B / D2);
  T gC = g[kConicA] * (-B * B / D2) + g[kConicB] * (A * B / D2) + g[kConicC] * (-A * A / D2);
  T g00 = 0, g01 = 0, g11 = 0;
  const T ratio = D0 / D;
  if (ratio > T(2.5e-5)) {
    const T k = g[kOpacity] * T(0.5) / std::sqrt(ratio);  // d sqrt(r) = dr / (2 sqrt r)
    // r = D0 / D: dr/dA = -D0 C / D^2 (through D), dr/ds00 = s11 / D (through D0), and alike.
    gA += k * (-D0 * C / D2), gB += k * (T(2) * D0 * B / D2), gC += k * (-D0 * A / D2);
    g00 += k * s11 / D, g01 += k * (T(-2) * s01) / D, g11 += k * s00 / D;
  }
  g00 += gA, g01 += gB, g11 += gC;  // A = s00 + lp, B = s01, C = s11 + lp
  // S0 = eps^2 J J^T + a w w^T with the symmetric gradient G = [[g00, g01/2], [g01/2, g11]].
  const T G[2][2] = {{g00, T(0.5) * g01}, {T(0.5) * g01, g11}};
  // dL/dw from a w w^T: 2 a G w; dL/da = w^T G w.
  T gw[2] = {T(2) * a * (G[0][0] * w[0] + G[0][1] * w[1]), T(2) * a * (G[1][0] * w[0] + G[1][1] * w[1])};
  const T ga = w[0] * (G[0][0] * w[0] + G[0][1] * w[1]) + w[1] * (G[1][0] * w[0] + G[1][1] * w[1]);
  // dL/dJ from eps^2 J J^T: 2 eps^2 G J.
  T gJ[2][3] = {};
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 3; ++j) gJ[i][j] = T(2) * gt.eps2 * (G[i][0] * J[0][j] + G[i][1] * J[1][j]);
  // Orientation o2 = (w0^2 - w1^2, -2 w0 w1) / n.
  {
    const T n = w[0] * w[0] + w[1] * w[1] + T(rp.orientation_guard);
    const T e = w[0] * w[0] - w[1] * w[1], f = T(-2) * w[0] * w[1];
    const T n2 = n * n;
    gw[0] += g[kOrientX] * (T(2) * w[0] * n - e * T(2) * w[0]) / n2 + g[kOrientY] * (T(-2) * w[1] * n - f * T(2) * w[0]) / n2;
    gw[1] += g[kOrientX] * (T(-2) * w[1] * n - e * T(2) * w[1]) / n2 + g[kOrientY] * (T(-2) * w[0] * n - f * T(2) * w[1]) / n2;
  }
  // w = J d: dL/dJ += gw d^T, dL/dd += J^T gw.
  T gd[3] = {J[0][0] * gw[0], J[1][1] * gw[1], J[0][2] * gw[0] + J[1][2] * gw[1]};
  gJ[0][0] += gw[0] * d[0], gJ[0][2] += gw[0] * d[2], gJ[1][1] += gw[1] * d[1], gJ[1][2] += gw[1] * d[2];
  // a = k^2 - eps^2 / (|d|^2 + delta^2): da/dd = 2 eps^2 d / s^2.
  for (int j = 0; j < 3; ++j) gd[j] += ga * T(2) * gt.eps2 * d[j] / (s * s);
  // J(m): J00 = fx/z, J11 = -fy/z, J02 = fx tx/z, J12 = -fy ty/z; z = -m.z.
  T gm[3] = {0, 0, 0};
  T gz = gJ[0][0] * (-fx / (z * z)) + gJ[1][1] * (fy / (z * z)) + gJ[0][2] * (-fx * tx / (z * z)) + gJ[1][2] * (fy * ty / (z * z));
  if (free_x) gm[0] += gJ[0][2] * fx / (z * z), gz += gJ[0][2] * (fx / z) * (-m[0] / (z * z));
  if (free_y) gm[1] += gJ[1][2] * (-fy) / (z * z), gz += gJ[1][2] * (-fy / z) * (-m[1] / (z * z));
  // Pixel mean and depth.
  gm[0] += g[kU] * fx / z, gz += g[kU] * (-fx * m[0] / (z * z));
  gm[1] += g[kV] * (-fy / z), gz += g[kV] * (fy * m[1] / (z * z));
  gz += g[kDepth];
  gm[2] += -gz;
  // Back to the world: mean = R mu + t, d = R dw.
  for (int j = 0; j < 3; ++j) {
    T gmu = 0, gdw = 0;
    for (int r = 0; r < 3; ++r) gmu += W[4 * r + j] * gm[r], gdw += W[4 * r + j] * gd[r];
    g_p0[j] += T(0.5) * gmu - gdw;
    g_p1[j] += T(0.5) * gmu + gdw;
  }
  return g[kConf];
}

// Projection of every segment of N strands of L points: proj (segments x kProjected).
template <class T>
void project_all(const std::vector<T>& points, const std::vector<T>& conf, std::uint32_t strands, std::uint32_t L,
                 const RasterCamera& cam, const RasterParams& rp, std::vector<T>& proj) {
  const std::uint32_t segs = L - 1;
  proj.assign(std::size_t(strands) * segs * kProjected, T(0));
  for (std::uint32_t s = 0; s < strands; ++s)
    for (std::uint32_t l = 0; l < segs; ++l) {
      const std::size_t gi = std::size_t(s) * segs + l;
      const T* p0 = &points[(std::size_t(s) * L + l) * 3];
      project_segment(p0, p0 + 3, conf[gi], cam, rp, &proj[gi * kProjected]);
    }
}

// Gaussians considered at a pixel, front to back (quantised depth, then index), as the tiles see them.
template <class T>
std::vector<std::uint32_t> pixel_order(const std::vector<T>& proj, const RasterCamera& cam, std::uint32_t px, std::uint32_t py) {
  std::vector<std::uint32_t> order;
  const std::size_t n = proj.size() / kProjected;
  const std::int64_t tx = px / kTile, ty = py / kTile;
  const std::int64_t ntx = tiles_x(cam), nty = tiles_y(cam);
  for (std::size_t i = 0; i < n; ++i) {
    const T* g = &proj[i * kProjected];
    if (g[kValid] == T(0)) continue;
    const double u = double(g[kU]), v = double(g[kV]), r = double(g[kRadius]);
    const std::int64_t x0 = std::clamp<std::int64_t>(std::int64_t(std::floor((u - r) / kTile)), 0, ntx - 1);
    const std::int64_t x1 = std::clamp<std::int64_t>(std::int64_t(std::floor((u + r) / kTile)), 0, ntx - 1);
    const std::int64_t y0 = std::clamp<std::int64_t>(std::int64_t(std::floor((v - r) / kTile)), 0, nty - 1);
    const std::int64_t y1 = std::clamp<std::int64_t>(std::int64_t(std::floor((v + r) / kTile)), 0, nty - 1);
    if (tx >= x0 && tx <= x1 && ty >= y0 && ty <= y1) order.push_back(std::uint32_t(i));
  }
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return quantise_depth(proj[a * kProjected + kDepth], cam) < quantise_depth(proj[b * kProjected + kDepth], cam);
  });
  return order;
}

// The transmittance cut-off sits between 0.01^2 and 0.01^3: two Gaussians clamped at 0.99 leave
// exactly 1e-4, and a cut-off there (3DGS's) would make the result flip on rounding.
inline constexpr double kAlphaMin = 1.0 / 255.0, kAlphaMax = 0.99, kTransmittanceMin = 5e-5;

// The opacity of a Gaussian at a pixel centre, 0 below the cut-off (see the top of this file).
template <class T>
T gaussian_alpha(const T* g, T qx, T qy, T* power_out = nullptr) {
  const T dx = qx - g[kU], dy = qy - g[kV];
  const T power = T(-0.5) * (g[kConicA] * dx * dx + T(2) * g[kConicB] * dx * dy + g[kConicC] * dy * dy);
  if (power_out) *power_out = power;
  if (power > T(0)) return T(0);
  const T raw = std::min(T(kAlphaMax), g[kOpacity] * std::exp(power));
  return raw < T(kAlphaMin) ? T(0) : (raw - T(kAlphaMin)) / (T(1) - T(kAlphaMin));
}

// The Gaussians that contribute at a pixel, front to back, and the transmittance left after them.
template <class T>
std::vector<std::uint32_t> pixel_contributors(const std::vector<T>& proj, const RasterCamera& cam, const std::vector<float>& body_depth,
                                              std::uint32_t px, std::uint32_t py, T& transmittance) {
  const double occluder = body_depth.empty() ? 1e30 : body_depth[std::size_t(py) * cam.width + px];
  std::vector<std::uint32_t> used;
  transmittance = T(1);
  for (std::uint32_t i : pixel_order(proj, cam, px, py)) {
    const T* g = &proj[std::size_t(i) * kProjected];
    if (double(g[kDepth]) > occluder) continue;
    const T alpha = gaussian_alpha(g, T(px) + T(0.5), T(py) + T(0.5));
    if (alpha <= T(0)) continue;
    const T next = transmittance * (T(1) - alpha);
    if (next < T(kTransmittanceMin)) break;
    used.push_back(i);
    transmittance = next;
  }
  return used;
}

// Compositing of all pixels: image (kChannels x H x W, planar). body_depth (H x W) may be empty.
template <class T>
void composite(const std::vector<T>& proj, const RasterCamera& cam, const std::vector<float>& body_depth, std::vector<T>& image) {
  const std::uint32_t W = cam.width, H = cam.height;
  image.assign(std::size_t(kChannels) * W * H, T(0));
  for (std::uint32_t py = 0; py < H; ++py)
    for (std::uint32_t px = 0; px < W; ++px) {
      const std::size_t pix = std::size_t(py) * W + px;
      T T_end;
      const std::vector<std::uint32_t> used = pixel_contributors(proj, cam, body_depth, px, py, T_end);
      T Tr = T(1), acc[kChannels] = {0, 0, 0, 0, 0};
      for (std::uint32_t i : used) {
        const T* g = &proj[std::size_t(i) * kProjected];
        const T alpha = gaussian_alpha(g, T(px) + T(0.5), T(py) + T(0.5));
        const T w = alpha * Tr;
        acc[1] += w * g[kOrientX], acc[2] += w * g[kOrientY], acc[3] += w * g[kConf], acc[4] += w * g[kDepth];
        Tr *= T(1) - alpha;
      }
      image[pix] = T(1) - T_end;
      for (int c = 1; c < kChannels; ++c) image[std::size_t(c) * W * H + pix] = acc[c];
    }
}

// Adjoint of composite: grad_image (kChannels x H x W) -> grad_proj (segments x kProjected), added.
template <class T>
void composite_adjoint(const std::vector<T>& proj, const RasterCamera& cam, const std::vector<float>& body_depth,
                       const std::vector<T>& grad_image, std::vector<T>& grad_proj) {
  const std::uint32_t W = cam.width, H = cam.height;
  grad_proj.resize(proj.size(), T(0));
  for (std::uint32_t py = 0; py < H; ++py)
    for (std::uint32_t px = 0; px < W; ++px) {
      const std::size_t pix = std::size_t(py) * W + px;
      T Tr;
      const std::vector<std::uint32_t> used = pixel_contributors(proj, cam, body_depth, px, py, Tr);
      T gimg[kChannels];
      for (int c = 0; c < kChannels; ++c) gimg[c] = grad_image[std::size_t(c) * W * H + pix];
      // Channel values per Gaussian: alpha channel counts 1 per weight... it is 1 - T, handled apart.
      T behind[kChannels] = {0, 0, 0, 0, 0};  // sum over later Gaussians of w_j f_j
      T T_after = Tr;                          // transmittance after the current Gaussian
      for (std::size_t k = used.size(); k-- > 0;) {
        const std::uint32_t i = used[k];
        const T* g = &proj[std::size_t(i) * kProjected];
        T* gg = &grad_proj[std::size_t(i) * kProjected];
        T power;
        const T alpha = gaussian_alpha(g, T(px) + T(0.5), T(py) + T(0.5), &power);
        const T Ti = T_after / std::max(T(1e-6), T(1) - alpha);
        const T f[kChannels] = {T(1), g[kOrientX], g[kOrientY], g[kConf], g[kDepth]};
        const T w = alpha * Ti;
        gg[kOrientX] += gimg[1] * w, gg[kOrientY] += gimg[2] * w, gg[kConf] += gimg[3] * w, gg[kDepth] += gimg[4] * w;
        // dC/dalpha_i = T_i f_i - behind / (1 - alpha_i), for every channel (alpha: f = 1).
        T g_alpha = 0;
        for (int c = 0; c < kChannels; ++c) g_alpha += gimg[c] * (Ti * f[c] - behind[c] / std::max(T(1e-6), T(1) - alpha));
        for (int c = 0; c < kChannels; ++c) behind[c] += w * f[c];
        T_after = Ti;
        if (g[kOpacity] * std::exp(power) >= T(kAlphaMax)) continue;  // clamped: no gradient
        // alpha = (o exp(power) - amin) / (1 - amin), power = -0.5 (a dx^2 + 2 b dx dy + c dy^2), d = q - u.
        const T dx = T(px) + T(0.5) - g[kU], dy = T(py) + T(0.5) - g[kV];
        const T scale = T(1) / (T(1) - T(kAlphaMin));
        const T g_power = g_alpha * scale * g[kOpacity] * std::exp(power);
        gg[kOpacity] += g_alpha * scale * std::exp(power);
        gg[kConicA] += g_power * T(-0.5) * dx * dx;
        gg[kConicB] += g_power * (-dx * dy);
        gg[kConicC] += g_power * T(-0.5) * dy * dy;
        gg[kU] += g_power * (g[kConicA] * dx + g[kConicB] * dy);
        gg[kV] += g_power * (g[kConicB] * dx + g[kConicC] * dy);
      }
    }
}

// The whole map: strand points (N x L x 3) and per-segment confidence -> image; and its adjoint.
template <class T>
void rasterize_ref(const std::vector<T>& points, const std::vector<T>& conf, std::uint32_t strands, std::uint32_t L,
                   const RasterCamera& cam, const RasterParams& rp, const std::vector<float>& body_depth, std::vector<T>& image) {
  std::vector<T> proj;
  project_all(points, conf, strands, L, cam, rp, proj);
  composite(proj, cam, body_depth, image);
}

template <class T>
void rasterize_adjoint_ref(const std::vector<T>& points, const std::vector<T>& conf, std::uint32_t strands, std::uint32_t L,
                           const RasterCamera& cam, const RasterParams& rp, const std::vector<float>& body_depth,
                           const std::vector<T>& grad_image, std::vector<T>& grad_points, std::vector<T>& grad_conf) {
  std::vector<T> proj, grad_proj;
  project_all(points, conf, strands, L, cam, rp, proj);
  grad_proj.assign(proj.size(), T(0));
  composite_adjoint(proj, cam, body_depth, grad_image, grad_proj);
  const std::uint32_t segs = L - 1;
  grad_points.assign(points.size(), T(0));
  grad_conf.assign(std::size_t(strands) * segs, T(0));
  for (std::uint32_t s = 0; s < strands; ++s)
    for (std::uint32_t l = 0; l < segs; ++l) {
      const std::size_t gi = std::size_t(s) * segs + l, p = (std::size_t(s) * L + l) * 3;
      grad_conf[gi] = project_segment_adjoint(&points[p], &points[p + 3], cam, rp, &grad_proj[gi * kProjected], &grad_points[p],
                                              &grad_points[p + 3]);
    }
}

}  // namespace nf::splat
