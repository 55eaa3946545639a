// Shared by shaders/fur/strand_bending.comp and strand_losses_{fwd,bwd}.comp: the guarded segment
// direction, the bending angle and the trilinear SDF, with their derivatives. The maths:
// engine/fur/strand_losses_ref.hpp.
#ifndef NF_STRAND_LOSSES_GLSL
#define NF_STRAND_LOSSES_GLSL

const float NF_BEND_GUARD = 1e-6;

vec3 nf_unit(vec3 d, float delta2) { return d / sqrt(dot(d, d) + delta2); }

vec3 nf_unit_adjoint(vec3 d, float delta2, vec3 grad_u) {
  const float n2 = dot(d, d) + delta2, n = sqrt(n2);
  return grad_u / n - d * (dot(d, grad_u) / (n2 * n));
}

// atan2(sqrt(|u x v|^2 + eps^2), u . v) and, when wanted, its derivatives along u and v.
float nf_bend(vec3 u, vec3 v) {
  const vec3 w = cross(u, v);
  return atan(sqrt(dot(w, w) + NF_BEND_GUARD * NF_BEND_GUARD), dot(u, v));
}
void nf_bend_adjoint(vec3 u, vec3 v, out vec3 du, out vec3 dv) {
  const vec3 w = cross(u, v);
  const float c = dot(u, v), s = sqrt(dot(w, w) + NF_BEND_GUARD * NF_BEND_GUARD);
  const float r = s * s + c * c;
  const float dc = -s / r, ds = c / r;
  du = v * dc + cross(v, w) * (ds / s);
  dv = u * dc + cross(w, u) * (ds / s);
}

#endif
