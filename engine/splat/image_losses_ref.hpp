#pragma once
// Image-space losses of strand splatting (paper: L_sil, L_dir; masked by the non-bald mask), H x W
// float32 row-major planes; orientation is 2 planes (o_x, then o_y), as the rasteriser's channels 1-2.
//   L_sil = sum_p weight_p |alpha_p - mask_p| / N_sil,          N_sil = max(sum_p weight_p, 1e-6)
//   L_dir = sum_p a_p w_p (t_p dmin_p - log t_p) / N_dir,        N_dir = max(sum_p w_p, 1e-6)
//   w_p = weight_p gabor_confidence_p, t_p = max(tau_p, 1e-4), beta_p = atan2(o_y, o_x) / 2,
//   r_p = (beta_p - gabor_angle_p) mod pi in [0, pi), dmin_p = min(r_p, pi - r_p) in [0, pi/2],
//   a_p = [|o_p| > 1e-6]: below it the angle is undefined and the whole term and its gradients are 0
//   (the gate is a jump of L_dir). Normalisers use targets only: weighted means over the fur region;
//   weight == 0 everywhere gives 0 losses and 0 gradients. Gradients (kinks take subgradient 0):
//   dL_sil/dalpha = weight sign(alpha - mask) / N_sil; dL_dir/dtau = a w (dmin - 1/tau) / N_dir for
//   tau > floor, 0 under the floor (the clamp is flat, as finite differences see it); dL_dir/do =
//   a w t s (-o_y, o_x) / (2 |o|^2 N_dir), s = +1 for r in (0, pi/2), -1 in (pi/2, pi), 0 at r = 0 or
//   pi/2. Exact, no epsilon: the gate bounds it by w t / (2 |o| N_dir) <= 5e5 w t / N_dir.
//
// Angles follow engine/orient (gabor_bank.hpp): the rasteriser writes o = sum_i c_i (cos 2 theta_i,
// sin 2 theta_i) with theta_i in that convention and c_i its compositing weight. The losses are fed
// back to the rasteriser as dL/dalpha, dL/do and dL/dtau with upstream factors dL/dL_sil and
// dL/dL_dir (the paper's 0.1 and 1000 are the caller's). Consequences of the guards: a pixel whose
// rendered confidence fell under the floor is no longer pulled up by -log tau (only L_sil acts
// there); dL/dtheta_i = dL/do . do/dtheta_i ~ c_i / |o| stays O(1) unless strands of crossing
// orientations cancel in o; raise orientation_min to damp that.
//
// Sums are accumulated in double whatever T is; per-pixel maths is in T, as the GPU does it in float.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace nf::splat {

struct ImageLossParams {
  double tau_floor = 1e-4;        // rendered confidence is used as max(tau, tau_floor)
  double orientation_min = 1e-6;  // |o| at or below this: no orientation term at the pixel
  double norm_floor = 1e-6;       // N_sil and N_dir are at least this
  std::uint64_t chunk_pixels = 0; // GPU only: pixels per dispatch, 0 = as many as a binding allows
};

// The differentiable inputs (from the rasteriser) and the targets of one view.
template <class T>
struct ImageLossInputs {
  std::span<const T> alpha;        // pixels
  std::span<const T> orientation;  // pixels * 2, planar: o_x plane then o_y plane
  std::span<const T> tau;          // pixels
};
template <class T>
struct ImageLossTargets {
  std::span<const T> mask;              // pixels, 0/1 or soft
  std::span<const T> weight;            // pixels, >= 0: the non-bald mask
  std::span<const T> gabor_angle;       // pixels, radians (any finite value; [0, pi) expected)
  std::span<const T> gabor_confidence;  // pixels, >= 0
};

// Forward output, also the layout of the 4-float `losses` buffer of the GPU wrapper.
template <class T>
struct ImageLossValues {
  T silhouette = 0, orientation = 0;            // L_sil, L_dir
  T silhouette_norm = 0, orientation_norm = 0;  // N_sil, N_dir (guarded)
};

template <class T>
struct ImageLossGradients {
  std::vector<T> alpha, orientation, tau;
};

constexpr double kImageLossPi = 3.14159265358979323846;

// The folded angle difference dmin in [0, pi/2] and its slope s = d dmin / d beta.
template <class T>
T image_loss_fold(T beta, T gabor_angle, T& slope) {
  const T pi = T(kImageLossPi), half = T(0.5) * pi;
  const T diff = beta - gabor_angle;
  const T r = diff - pi * std::floor(diff / pi);
  slope = (r > T(0) && r < half) ? T(1) : (r > half && r < pi) ? T(-1) : T(0);
  return std::min(r, pi - r);
}

// The orientation term a_p (t dmin - log t) of one pixel without w_p; false when a_p = 0.
template <class T>
bool image_loss_orientation_term(T ox, T oy, T tau, T gabor_angle, const ImageLossParams& p, T& term, T& dmin,
                                 T& slope) {
  const T len2 = ox * ox + oy * oy;
  const T omin = T(p.orientation_min);
  if (!(len2 > omin * omin)) return false;
  const T t = std::max(tau, T(p.tau_floor));
  dmin = image_loss_fold(T(0.5) * std::atan2(oy, ox), gabor_angle, slope);
  term = t * dmin - std::log(t);
  return true;
}

template <class T>
ImageLossValues<T> image_losses_forward_ref(std::uint64_t pixels, const ImageLossInputs<T>& in,
                                            const ImageLossTargets<T>& tg, const ImageLossParams& p) {
  double sil = 0, dir = 0, nsil = 0, ndir = 0;
  for (std::uint64_t i = 0; i < pixels; ++i) {
    const T weight = tg.weight[i];
    if (!(weight > T(0))) continue;
    nsil += double(weight);
    sil += double(weight * std::fabs(in.alpha[i] - tg.mask[i]));
    const T w = weight * tg.gabor_confidence[i];
    if (!(w > T(0))) continue;
    ndir += double(w);
    T term, dmin, slope;
    if (image_loss_orientation_term(in.orientation[i], in.orientation[pixels + i], in.tau[i], tg.gabor_angle[i], p,
                                    term, dmin, slope))
      dir += double(w * term);
  }
  ImageLossValues<T> v;
  v.silhouette_norm = T(std::max(nsil, p.norm_floor));
  v.orientation_norm = T(std::max(ndir, p.norm_floor));
  v.silhouette = T(sil / std::max(nsil, p.norm_floor));
  v.orientation = T(dir / std::max(ndir, p.norm_floor));
  return v;
}

// Adjoint: given dL/dL_sil and dL/dL_dir, the gradients w.r.t. alpha, orientation and tau.
// `norms` are the forward's silhouette_norm and orientation_norm.
template <class T>
ImageLossGradients<T> image_losses_backward_ref(std::uint64_t pixels, const ImageLossInputs<T>& in,
                                                const ImageLossTargets<T>& tg, const ImageLossParams& p,
                                                const ImageLossValues<T>& norms, T grad_silhouette,
                                                T grad_orientation) {
  ImageLossGradients<T> g;
  g.alpha.assign(pixels, T(0));
  g.orientation.assign(pixels * 2, T(0));
  g.tau.assign(pixels, T(0));
  const T ks = grad_silhouette / norms.silhouette_norm, kd = grad_orientation / norms.orientation_norm;
  for (std::uint64_t i = 0; i < pixels; ++i) {
    const T weight = tg.weight[i];
    if (!(weight > T(0))) continue;
    const T r = in.alpha[i] - tg.mask[i];
    g.alpha[i] = ks * weight * T((r > T(0)) - (r < T(0)));
    const T w = weight * tg.gabor_confidence[i];
    if (!(w > T(0))) continue;
    const T ox = in.orientation[i], oy = in.orientation[pixels + i], tau = in.tau[i];
    T term, dmin, slope;
    if (!image_loss_orientation_term(ox, oy, tau, tg.gabor_angle[i], p, term, dmin, slope)) continue;
    const T kw = kd * w;
    if (tau > T(p.tau_floor)) g.tau[i] = kw * (dmin - T(1) / tau);
    const T t = std::max(tau, T(p.tau_floor));
    const T c = kw * t * slope * T(0.5) / (ox * ox + oy * oy);  // d beta / d o = (-o_y, o_x) / (2 |o|^2)
    g.orientation[i] = -c * oy;
    g.orientation[pixels + i] = c * ox;
  }
  return g;
}

}  // namespace nf::splat
