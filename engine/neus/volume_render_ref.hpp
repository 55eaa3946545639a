#pragma once
// NeuS volume rendering (Wang et al. 2021, official code: the compositing of render_core), given
// per-sample network outputs. R rays, S samples each (S fixed per call), rays independent.
// Layouts (row-major, ray-major): sdf, cos, dist [R*S]; rgb [R*S*3]; colour [R*3]; opacity [R].
//   iter_cos_i = -(relu(0.5 - 0.5 cos_i) (1 - a) + relu(-cos_i) a),  a = cos_anneal in [0, 1] (fixed)
//   h_i = iter_cos_i dist_i / 2,  prev_i = sdf_i - h_i,  next_i = sdf_i + h_i
//   p_i = sigmoid(prev_i s),  c_i = sigmoid(next_i s),  s = inv_s > 0 (one scalar per call)
//   alpha_i = clamp((p_i - c_i + 1e-5) / (p_i + 1e-5), 0, 1)
//   T_0 = 1, T_{i+1} = T_i (1 - alpha_i + 1e-7),  w_i = alpha_i T_i
//   colour = sum_i w_i rgb_i,  opacity = sum_i w_i
// Adjoint for L = sum_r (gcol_r . colour_r + gop_r opacity_r); with g_i = gcol . rgb_i + gop:
//   dL/drgb_i = w_i gcol;  dL/dalpha_i = T_i (g_i - R_{i+1}), where R is the suffix "remaining
//   radiance at unit transmittance": R_S = 0, R_i = alpha_i g_i + (1 - alpha_i + 1e-7) R_{i+1}.
//   Exact and division-free: the backward walks i = S-1..0 keeping R, with T_i from a forward sweep
//   (the GPU stashes T_i in the grad_sdf slots of its own ray, then overwrites them).
//   dalpha/dp = c / (p + 1e-5)^2, dalpha/dc = -1 / (p + 1e-5), zero where the clamp is active
//   (raw < 0 or raw > 1; with iter_cos <= 0 we have p >= c, so raw is in (0, 1] up to rounding);
//   dp/dprev = s sigma'(prev s), dp/ds = prev sigma'(prev s) (same for c with next);
//   diter_cos/dcos = 0.5 (1 - a) [cos < 1] + a [cos < 0]: the relu kinks take subgradient 0.
//   dL/dinv_s is summed over all rays and samples. dist is not differentiated.
// sigmoid and sigma'(x) = e^{-|x|} / (1 + e^{-|x|})^2 are evaluated without overflow for any x.
// Per-ray sums are in T, as the GPU does them in float.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace nf::neus {

template <class T>
struct VolumeRenderInputs {
  std::span<const T> sdf, cos, dist, rgb;
  T inv_s = T(64);
};
template <class T>
struct VolumeRenderOutputs {
  std::vector<T> colour, opacity;
};
template <class T>
struct VolumeRenderGradients {
  std::vector<T> sdf, cos, rgb;
  T inv_s = T(0);
};

namespace detail {

template <class T>
T nf_sigmoid(T x) {
  if (x >= T(0)) return T(1) / (T(1) + std::exp(-x));
  const T e = std::exp(x);
  return e / (T(1) + e);
}
template <class T>
T nf_sigmoid_derivative(T x) {
  const T e = std::exp(-std::fabs(x));
  return e / ((T(1) + e) * (T(1) + e));
}

// Per-sample forward and the partials the adjoint needs.
template <class T>
struct Sample {
  T alpha, dalpha_dsdf, dalpha_dcos, dalpha_ds;
};
template <class T>
Sample<T> sample(T sdf, T cos, T dist, T s, T anneal) {
  const T iter_cos = -(std::max(T(0.5) - T(0.5) * cos, T(0)) * (T(1) - anneal) + std::max(-cos, T(0)) * anneal);
  const T h = iter_cos * dist * T(0.5);
  const T prev = sdf - h, next = sdf + h;
  const T p = nf_sigmoid(prev * s), c = nf_sigmoid(next * s);
  const T den = p + T(1e-5);
  const T raw = (p - c + T(1e-5)) / den;
  Sample<T> r{std::clamp(raw, T(0), T(1)), T(0), T(0), T(0)};
  if (raw < T(0) || raw > T(1)) return r;
  const T da_dp = c / (den * den), da_dc = -T(1) / den;
  const T sp = nf_sigmoid_derivative(prev * s), sc = nf_sigmoid_derivative(next * s);
  const T dprev = da_dp * s * sp, dnext = da_dc * s * sc;  // dalpha/dprev, dalpha/dnext
  r.dalpha_dsdf = dprev + dnext;
  const T diter = T(0.5) * (T(1) - anneal) * (cos < T(1) ? T(1) : T(0)) + anneal * (cos < T(0) ? T(1) : T(0));
  r.dalpha_dcos = (dnext - dprev) * T(0.5) * dist * diter;
  r.dalpha_ds = da_dp * prev * sp + da_dc * next * sc;
  return r;
}

}  // namespace detail

template <class T>
VolumeRenderOutputs<T> volume_render_forward_ref(std::uint64_t rays, std::uint32_t samples,
                                                 const VolumeRenderInputs<T>& in, double cos_anneal) {
  VolumeRenderOutputs<T> out{std::vector<T>(rays * 3, T(0)), std::vector<T>(rays, T(0))};
  const T a = T(cos_anneal);
  for (std::uint64_t r = 0; r < rays; ++r) {
    T trans = T(1), col[3] = {T(0), T(0), T(0)}, op = T(0);
    for (std::uint32_t i = 0; i < samples; ++i) {
      const std::uint64_t k = r * samples + i;
      const T alpha = detail::sample(in.sdf[k], in.cos[k], in.dist[k], in.inv_s, a).alpha;
      const T w = alpha * trans;
      for (int ch = 0; ch < 3; ++ch) col[ch] += w * in.rgb[k * 3 + ch];
      op += w;
      trans *= T(1) - alpha + T(1e-7);
    }
    for (int ch = 0; ch < 3; ++ch) out.colour[r * 3 + ch] = col[ch];
    out.opacity[r] = op;
  }
  return out;
}

template <class T>
VolumeRenderGradients<T> volume_render_backward_ref(std::uint64_t rays, std::uint32_t samples,
                                                    const VolumeRenderInputs<T>& in, double cos_anneal,
                                                    std::span<const T> grad_colour, std::span<const T> grad_opacity) {
  const std::uint64_t n = rays * samples;
  VolumeRenderGradients<T> g{std::vector<T>(n, T(0)), std::vector<T>(n, T(0)), std::vector<T>(n * 3, T(0)), T(0)};
  const T a = T(cos_anneal);
  std::vector<T> trans(samples);
  double ds_total = 0;
  for (std::uint64_t r = 0; r < rays; ++r) {
    T t = T(1);
    for (std::uint32_t i = 0; i < samples; ++i) {
      const std::uint64_t k = r * samples + i;
      trans[i] = t;
      t *= T(1) - detail::sample(in.sdf[k], in.cos[k], in.dist[k], in.inv_s, a).alpha + T(1e-7);
    }
    const T gc[3] = {grad_colour[r * 3], grad_colour[r * 3 + 1], grad_colour[r * 3 + 2]};
    const T go = grad_opacity[r];
    T rest = T(0), ds = T(0);
    for (std::uint32_t i = samples; i-- > 0;) {
      const std::uint64_t k = r * samples + i;
      const auto sm = detail::sample(in.sdf[k], in.cos[k], in.dist[k], in.inv_s, a);
      const T gi = gc[0] * in.rgb[k * 3] + gc[1] * in.rgb[k * 3 + 1] + gc[2] * in.rgb[k * 3 + 2] + go;
      const T w = sm.alpha * trans[i];
      for (int ch = 0; ch < 3; ++ch) g.rgb[k * 3 + ch] = w * gc[ch];
      const T ga = trans[i] * (gi - rest);
      g.sdf[k] = ga * sm.dalpha_dsdf;
      g.cos[k] = ga * sm.dalpha_dcos;
      ds += ga * sm.dalpha_ds;
      rest = sm.alpha * gi + (T(1) - sm.alpha + T(1e-7)) * rest;
    }
    ds_total += double(ds);
  }
  g.inv_s = T(ds_total);
  return g;
}

}  // namespace nf::neus
