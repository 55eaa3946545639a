#version 460
#extension GL_GOOGLE_include_directive : require
// Adjoint of image_losses_fwd: one invocation per pixel writes dL/dalpha, dL/do (x and y planes) and
// dL/dtau for L = grad_silhouette * L_sil + grad_orientation * L_dir, with the normalisers N_sil,
// N_dir read from the forward's `losses` (a uniform: 12 storage bindings are all the shared layout
// has). Pure gathers: no atomics, deterministic. pc.shift[b]: where binding b's data begins.
// Host wrapper: engine/splat/image_losses.cpp; maths: engine/splat/image_losses_ref.hpp.

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_image_losses.glsl"

layout(std430, binding = 0) readonly buffer Alpha { float alpha[]; };
layout(std430, binding = 1) readonly buffer OrientationX { float orientation_x[]; };
layout(std430, binding = 2) readonly buffer OrientationY { float orientation_y[]; };
layout(std430, binding = 3) readonly buffer Tau { float tau[]; };
layout(std430, binding = 4) readonly buffer Mask { float mask[]; };
layout(std430, binding = 5) readonly buffer Weight { float weight[]; };
layout(std430, binding = 6) readonly buffer GaborAngle { float gabor_angle[]; };
layout(std430, binding = 7) readonly buffer GaborConfidence { float gabor_confidence[]; };
layout(std430, binding = 8) writeonly buffer GradAlpha { float grad_alpha[]; };
layout(std430, binding = 9) writeonly buffer GradOrientationX { float grad_orientation_x[]; };
layout(std430, binding = 10) writeonly buffer GradOrientationY { float grad_orientation_y[]; };
layout(std430, binding = 11) writeonly buffer GradTau { float grad_tau[]; };
layout(std140, binding = 12) uniform Losses { vec4 losses; };  // L_sil, L_dir, N_sil, N_dir

layout(push_constant) uniform Push {
  uint n;  // pixels in this chunk
  float tau_floor;
  float omin2;
  float grad_silhouette;   // dL/dL_sil
  float grad_orientation;  // dL/dL_dir
  uint shift[12];          // bindings 0..11
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.n) return;
  float ga = 0.0, gt = 0.0;
  vec2 go = vec2(0.0);
  const float wt = weight[pc.shift[5] + i];
  if (wt > 0.0) {  // zero weight: zero gradients, nothing else is read
    const float r = alpha[pc.shift[0] + i] - mask[pc.shift[4] + i];
    ga = (pc.grad_silhouette / losses.z) * wt * sign(r);
    const float w = wt * gabor_confidence[pc.shift[7] + i];
    if (w > 0.0) {
      const vec2 o = vec2(orientation_x[pc.shift[1] + i], orientation_y[pc.shift[2] + i]);
      const float tv = tau[pc.shift[3] + i];
      float term, dmin, slope;
      if (nf_image_loss_orientation_term(o, tv, gabor_angle[pc.shift[6] + i], pc.tau_floor, pc.omin2, term, dmin,
                                         slope)) {
        const float kw = (pc.grad_orientation / losses.w) * w;
        if (tv > pc.tau_floor) gt = kw * (dmin - 1.0 / tv);
        const float c = kw * max(tv, pc.tau_floor) * slope * 0.5 / dot(o, o);
        go = c * vec2(-o.y, o.x);
      }
    }
  }
  grad_alpha[pc.shift[8] + i] = ga;
  grad_orientation_x[pc.shift[9] + i] = go.x;
  grad_orientation_y[pc.shift[10] + i] = go.y;
  grad_tau[pc.shift[11] + i] = gt;
}
