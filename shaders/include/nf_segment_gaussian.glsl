// The segment-to-Gaussian covariance and its adjoint (maths and guard explained in
// engine/splat/segment_gaussian_ref.hpp, which is the CPU twin of these functions).
#ifndef NF_SEGMENT_GAUSSIAN_GLSL
#define NF_SEGMENT_GAUSSIAN_GLSL

// Stored covariance (xx, xy, xz, yy, yz, zz) of the segment with direction vector d.
void nf_segment_covariance(vec3 d, float k2, float eps2, float delta2, out float cov[6]) {
  const float a = k2 - eps2 / (dot(d, d) + delta2);
  cov[0] = eps2 + a * d.x * d.x;
  cov[1] = a * d.x * d.y;
  cov[2] = a * d.x * d.z;
  cov[3] = eps2 + a * d.y * d.y;
  cov[4] = a * d.y * d.z;
  cov[5] = eps2 + a * d.z * d.z;
}

// dL/dd from dL/dcov (stored form; each off-diagonal stands for both symmetric entries).
vec3 nf_segment_covariance_adjoint(vec3 d, float g[6], float k2, float eps2, float delta2) {
  const float s = dot(d, d) + delta2;
  const float a = k2 - eps2 / s;
  const vec3 hd = vec3(g[0] * d.x + 0.5 * (g[1] * d.y + g[2] * d.z),
                       g[3] * d.y + 0.5 * (g[1] * d.x + g[4] * d.z),
                       g[5] * d.z + 0.5 * (g[2] * d.x + g[4] * d.y));
  const float radial = 2.0 * (eps2 / s) * (dot(d, hd) / s);
  return 2.0 * a * hd + radial * d;
}

#endif
