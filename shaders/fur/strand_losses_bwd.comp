#version 460
#extension GL_GOOGLE_include_directive : require
// Adjoint of the geometric strand losses: dLoss/dpoints for Loss = w_dir L_dir + w_shape L_shape +
// w_pen L_pen (the normalisations included). One invocation per strand: a strand's points belong to
// it alone, so no atomics. The batch mean's derivative cancels (strand_losses_ref.hpp).

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_strand_losses.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };
layout(std430, binding = 1) readonly buffer Guides { float guides[]; };
layout(std430, binding = 2) readonly buffer Lengths { float lengths[]; };
layout(std430, binding = 3) readonly buffer Theta { float theta[]; };
layout(std430, binding = 4) readonly buffer Mean { float mean_theta[]; };
layout(std430, binding = 5) readonly buffer Sdf { float sdf[]; };
layout(std430, binding = 6) buffer GradPoints { float grad_points[]; };  // strands * L * 3

layout(push_constant) uniform Push {
  uint strands;
  uint points_per_strand;
  float guard_fraction;
  int nx, ny, nz;
  float ox, oy, oz;
  float spacing;
  float w_direction, w_curvature, w_penetration;  // dLoss/dL_t
  uint accumulate;  // 1: add to grad_points
} pc;

#include "nf_strand_sdf.glsl"

vec3 point(uint i) { return vec3(points[3u * i], points[3u * i + 1u], points[3u * i + 2u]); }
void add(uint i, vec3 g) {
  grad_points[3u * i] += g.x;
  grad_points[3u * i + 1u] += g.y;
  grad_points[3u * i + 2u] += g.z;
}

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.strands) return;
  const uint L = pc.points_per_strand, first = s * L, S = L - 1u, B = L - 2u;
  const float N = float(pc.strands);
  const float delta = pc.guard_fraction * lengths[s] / float(S), delta2 = delta * delta;
  const vec3 g = vec3(guides[3u * s], guides[3u * s + 1u], guides[3u * s + 2u]);
  if (pc.accumulate == 0u)
    for (uint k = 0u; k < L; ++k) {
      grad_points[3u * (first + k)] = 0.0;
      grad_points[3u * (first + k) + 1u] = 0.0;
      grad_points[3u * (first + k) + 2u] = 0.0;
    }
  // Walk the segments keeping the gradient of the current direction, which the next bend adds to.
  vec3 d_prev = vec3(0.0), b_prev = vec3(0.0), gb_prev = vec3(0.0);
  for (uint l = 0u; l < S; ++l) {
    const vec3 d = point(first + l + 1u) - point(first + l);
    const vec3 b = nf_unit(d, delta2);
    vec3 gb = -dot(b, g) > 0.0 ? g * (-pc.w_direction * float(l) / float(S) / (N * float(S))) : vec3(0.0);
    if (l > 0u) {
      vec3 du, dv;
      nf_bend_adjoint(b_prev, b, du, dv);
      const float k = pc.w_curvature * 2.0 * (theta[s * B + l - 1u] - mean_theta[l - 1u]) / (N * float(B));
      gb_prev += du * k;
      gb += dv * k;
      // Segment l - 1 is complete: move its gradient onto its two points.
      const vec3 gd = nf_unit_adjoint(d_prev, delta2, gb_prev);
      add(first + l - 1u, -gd);
      add(first + l, gd);
    }
    d_prev = d, b_prev = b, gb_prev = gb;
  }
  const vec3 gd = nf_unit_adjoint(d_prev, delta2, gb_prev);
  add(first + S - 1u, -gd);
  add(first + S, gd);
  for (uint k = 0u; k < L; ++k) {
    vec3 grad;
    if (nf_sdf_sample(point(first + k), true, grad) < 0.0) add(first + k, grad * (-pc.w_penetration / (N * float(L))));
  }
}
