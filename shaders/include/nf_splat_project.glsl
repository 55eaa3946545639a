// Projection of one strand segment to a screen-space Gaussian, and its adjoint: the GLSL twin of
// project_segment / project_segment_adjoint in engine/splat/rasterizer_ref.hpp (maths, guards and
// the layout of the 12 floats are documented there). Needs the push-constant block `pc` with the
// camera and Gaussian fields used below.
#ifndef NF_SPLAT_PROJECT_GLSL
#define NF_SPLAT_PROJECT_GLSL

const uint P_U = 0u, P_V = 1u, P_CA = 2u, P_CB = 3u, P_CC = 4u, P_OPACITY = 5u, P_DEPTH = 6u, P_OX = 7u, P_OY = 8u,
           P_CONF = 9u, P_RADIUS = 10u, P_VALID = 11u, P_FLOATS = 12u;

struct SegmentCamera {
  vec3 m;   // camera-space mean
  vec3 d;   // camera-space segment vector
  float z;  // depth
};

SegmentCamera nf_segment_to_camera(vec3 p0, vec3 p1) {
  const vec3 mu = 0.5 * (p0 + p1), dw = p1 - p0;
  SegmentCamera s;
  s.m = vec3(dot(pc.r0.xyz, mu) + pc.r0.w, dot(pc.r1.xyz, mu) + pc.r1.w, dot(pc.r2.xyz, mu) + pc.r2.w);
  s.d = vec3(dot(pc.r0.xyz, dw), dot(pc.r1.xyz, dw), dot(pc.r2.xyz, dw));
  s.z = -s.m.z;
  return s;
}

vec2 nf_fov_limits() {
  return 1.3 * vec2(max(pc.cx, float(pc.width) - pc.cx) / pc.fx, max(pc.cy, float(pc.height) - pc.cy) / pc.fy);
}

// Writes the 12 floats; returns false (and zeros) when culled.
bool nf_project_segment(vec3 p0, vec3 p1, float conf, out float o[12]) {
  for (uint i = 0u; i < P_FLOATS; ++i) o[i] = 0.0;
  const SegmentCamera s = nf_segment_to_camera(p0, p1);
  const float z = s.z;
  if (!(z >= pc.near_plane) || !(z <= pc.far_plane)) return false;
  const vec2 lim = nf_fov_limits();
  const float tx = clamp(s.m.x / z, -lim.x, lim.x), ty = clamp(s.m.y / z, -lim.y, lim.y);
  const float j00 = pc.fx / z, j02 = pc.fx * tx / z, j11 = -pc.fy / z, j12 = -pc.fy * ty / z;
  const vec3 d = s.d;
  const float a = pc.k2 - pc.eps2 / (dot(d, d) + pc.delta2);
  const vec2 w = vec2(j00 * d.x + j02 * d.z, j11 * d.y + j12 * d.z);
  const float jj00 = j00 * j00 + j02 * j02, jj01 = j02 * j12, jj11 = j11 * j11 + j12 * j12;
  const float s00 = pc.eps2 * jj00 + a * w.x * w.x, s01 = pc.eps2 * jj01 + a * w.x * w.y, s11 = pc.eps2 * jj11 + a * w.y * w.y;
  const float A = s00 + pc.low_pass, B = s01, C = s11 + pc.low_pass;
  const float det = A * C - B * B, det0 = s00 * s11 - s01 * s01;
  if (!(det > 0.0)) return false;
  const float opacity = sqrt(max(det0 / det, 2.5e-5));
  const float mid = 0.5 * (A + C);
  const float lambda = mid + sqrt(max(0.1, mid * mid - det));
  const float radius = ceil(3.5 * sqrt(lambda));
  const float u = pc.cx + pc.fx * s.m.x / z, v = pc.cy - pc.fy * s.m.y / z;
  if (u + radius <= 0.0 || v + radius <= 0.0 || u - radius >= float(pc.width) || v - radius >= float(pc.height)) return false;
  const float n = dot(w, w) + pc.orientation_guard;
  o[P_U] = u;
  o[P_V] = v;
  o[P_CA] = C / det;
  o[P_CB] = -B / det;
  o[P_CC] = A / det;
  o[P_OPACITY] = opacity;
  o[P_DEPTH] = z;
  o[P_OX] = (w.x * w.x - w.y * w.y) / n;
  o[P_OY] = -2.0 * w.x * w.y / n;
  o[P_CONF] = conf;
  o[P_RADIUS] = radius;
  o[P_VALID] = 1.0;
  return true;
}

// Adjoint: g (12 floats, radius/valid ignored) -> dL/dp0, dL/dp1 (returned through out params).
void nf_project_segment_adjoint(vec3 p0, vec3 p1, float g[12], out vec3 g_p0, out vec3 g_p1) {
  const SegmentCamera s = nf_segment_to_camera(p0, p1);
  const float z = s.z, z2 = z * z;
  const vec2 lim = nf_fov_limits();
  const float rx = s.m.x / z, ry = s.m.y / z;
  const bool free_x = rx > -lim.x && rx < lim.x, free_y = ry > -lim.y && ry < lim.y;
  const float tx = clamp(rx, -lim.x, lim.x), ty = clamp(ry, -lim.y, lim.y);
  const float j00 = pc.fx / z, j02 = pc.fx * tx / z, j11 = -pc.fy / z, j12 = -pc.fy * ty / z;
  const vec3 d = s.d;
  const float sd = dot(d, d) + pc.delta2;
  const float a = pc.k2 - pc.eps2 / sd;
  const vec2 w = vec2(j00 * d.x + j02 * d.z, j11 * d.y + j12 * d.z);
  const float jj00 = j00 * j00 + j02 * j02, jj01 = j02 * j12, jj11 = j11 * j11 + j12 * j12;
  const float s00 = pc.eps2 * jj00 + a * w.x * w.x, s01 = pc.eps2 * jj01 + a * w.x * w.y, s11 = pc.eps2 * jj11 + a * w.y * w.y;
  const float A = s00 + pc.low_pass, B = s01, C = s11 + pc.low_pass;
  const float D = A * C - B * B, D0 = s00 * s11 - s01 * s01, D2 = D * D;

  float gA = g[P_CA] * (-C * C / D2) + g[P_CB] * (B * C / D2) + g[P_CC] * (-B * B / D2);
  float gB = g[P_CA] * (2.0 * B * C / D2) + g[P_CB] * (-1.0 / D - 2.0 * B * B / D2) + g[P_CC] * (2.0 * A * B / D2);
  float gC = g[P_CA] * (-B * B / D2) + g[P_CB] * (A * B / D2) + g[P_CC] * (-A * A / D2);
  float g00 = 0.0, g01 = 0.0, g11 = 0.0;
  const float ratio = D0 / D;
  if (ratio > 2.5e-5) {
    const float k = g[P_OPACITY] * 0.5 / sqrt(ratio);
    gA += k * (-D0 * C / D2);
    gB += k * (2.0 * D0 * B / D2);
    gC += k * (-D0 * A / D2);
    g00 += k * s11 / D;
    g01 += k * (-2.0 * s01) / D;
    g11 += k * s00 / D;
  }
  g00 += gA;
  g01 += gB;
  g11 += gC;
  const mat2 G = mat2(g00, 0.5 * g01, 0.5 * g01, g11);  // symmetric
  vec2 gw = 2.0 * a * (G * w);
  const float ga = dot(w, G * w);
  // dL/dJ from eps^2 J J^T: 2 eps^2 G J (only the non-zero entries of J matter).
  float gj00 = 2.0 * pc.eps2 * (G[0][0] * j00);
  float gj02 = 2.0 * pc.eps2 * (G[0][0] * j02 + G[1][0] * j12);
  float gj11 = 2.0 * pc.eps2 * (G[1][1] * j11);
  float gj12 = 2.0 * pc.eps2 * (G[0][1] * j02 + G[1][1] * j12);
  {
    const float n = dot(w, w) + pc.orientation_guard, n2 = n * n;
    const float e = w.x * w.x - w.y * w.y, f = -2.0 * w.x * w.y;
    gw.x += g[P_OX] * (2.0 * w.x * n - e * 2.0 * w.x) / n2 + g[P_OY] * (-2.0 * w.y * n - f * 2.0 * w.x) / n2;
    gw.y += g[P_OX] * (-2.0 * w.y * n - e * 2.0 * w.y) / n2 + g[P_OY] * (-2.0 * w.x * n - f * 2.0 * w.y) / n2;
  }
  vec3 gd = vec3(j00 * gw.x, j11 * gw.y, j02 * gw.x + j12 * gw.y);
  gj00 += gw.x * d.x;
  gj02 += gw.x * d.z;
  gj11 += gw.y * d.y;
  gj12 += gw.y * d.z;
  gd += ga * 2.0 * pc.eps2 * d / (sd * sd);
  vec3 gm = vec3(0.0);
  float gz = gj00 * (-pc.fx / z2) + gj11 * (pc.fy / z2) + gj02 * (-pc.fx * tx / z2) + gj12 * (pc.fy * ty / z2);
  if (free_x) {
    gm.x += gj02 * pc.fx / z2;
    gz += gj02 * (pc.fx / z) * (-s.m.x / z2);
  }
  if (free_y) {
    gm.y += gj12 * (-pc.fy) / z2;
    gz += gj12 * (-pc.fy / z) * (-s.m.y / z2);
  }
  gm.x += g[P_U] * pc.fx / z;
  gz += g[P_U] * (-pc.fx * s.m.x / z2);
  gm.y += g[P_V] * (-pc.fy / z);
  gz += g[P_V] * (pc.fy * s.m.y / z2);
  gz += g[P_DEPTH];
  gm.z -= gz;
  // R^T: world = columns of the rows.
  const vec3 gmu = pc.r0.xyz * gm.x + pc.r1.xyz * gm.y + pc.r2.xyz * gm.z;
  const vec3 gdw = pc.r0.xyz * gd.x + pc.r1.xyz * gd.y + pc.r2.xyz * gd.z;
  g_p0 = 0.5 * gmu - gdw;
  g_p1 = 0.5 * gmu + gdw;
}

#endif
