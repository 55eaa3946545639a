// Per-pixel terms of the image-space losses of strand splatting, shared by
// shaders/splat/image_losses_{fwd,bwd}.comp. CPU twin and the formulas, guards and kink conventions:
// engine/splat/image_losses_ref.hpp.
#ifndef NF_IMAGE_LOSSES_GLSL
#define NF_IMAGE_LOSSES_GLSL

const float NF_IMAGE_LOSS_PI = 3.14159265358979323846;

// dmin = min(r, pi - r), r = (beta - gabor_angle) mod pi; slope = d dmin / d beta (0 at the kinks).
float nf_image_loss_fold(float beta, float gabor_angle, out float slope) {
  const float pi = NF_IMAGE_LOSS_PI, half_pi = 0.5 * NF_IMAGE_LOSS_PI;
  const float diff = beta - gabor_angle;
  const float r = diff - pi * floor(diff / pi);
  slope = (r > 0.0 && r < half_pi) ? 1.0 : (r > half_pi && r < pi) ? -1.0 : 0.0;
  return min(r, pi - r);
}

// a_p (t dmin - log t) without w_p; false where |o|^2 <= orientation_min^2 (no term, no gradient).
bool nf_image_loss_orientation_term(vec2 o, float tau, float gabor_angle, float tau_floor, float omin2,
                                    out float term, out float dmin, out float slope) {
  term = 0.0;
  dmin = 0.0;
  slope = 0.0;
  if (!(dot(o, o) > omin2)) return false;
  const float t = max(tau, tau_floor);
  dmin = nf_image_loss_fold(0.5 * atan(o.y, o.x), gabor_angle, slope);
  term = t * dmin - log(t);
  return true;
}

#endif
