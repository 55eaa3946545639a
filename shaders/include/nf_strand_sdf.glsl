// Trilinear sampling of the bald body's SDF grid (buffer `sdf`, push constants nx ny nz, ox oy oz,
// spacing), clamped to the grid's box with a zero gradient along a clamped axis. Include after the
// `Sdf` buffer and the push-constant block. Maths: engine/fur/strand_losses_ref.hpp (sdf_sample).
#ifndef NF_STRAND_SDF_GLSL
#define NF_STRAND_SDF_GLSL

float nf_sdf_at(int x, int y, int z) { return sdf[(uint(z) * uint(pc.ny) + uint(y)) * uint(pc.nx) + uint(x)]; }

float nf_sdf_sample(vec3 p, bool want_gradient, out vec3 gradient) {
  const vec3 q = (p - vec3(pc.ox, pc.oy, pc.oz)) / pc.spacing;
  const ivec3 dims = ivec3(pc.nx, pc.ny, pc.nz);
  const vec3 hi = vec3(dims - 1);
  const bvec3 inside = bvec3(q.x > 0.0 && q.x < hi.x, q.y > 0.0 && q.y < hi.y, q.z > 0.0 && q.z < hi.z);
  const vec3 c = clamp(q, vec3(0.0), hi);
  const ivec3 i0 = min(ivec3(c), dims - 2);
  const vec3 f = c - vec3(i0);
  const float v000 = nf_sdf_at(i0.x, i0.y, i0.z), v100 = nf_sdf_at(i0.x + 1, i0.y, i0.z);
  const float v010 = nf_sdf_at(i0.x, i0.y + 1, i0.z), v110 = nf_sdf_at(i0.x + 1, i0.y + 1, i0.z);
  const float v001 = nf_sdf_at(i0.x, i0.y, i0.z + 1), v101 = nf_sdf_at(i0.x + 1, i0.y, i0.z + 1);
  const float v011 = nf_sdf_at(i0.x, i0.y + 1, i0.z + 1), v111 = nf_sdf_at(i0.x + 1, i0.y + 1, i0.z + 1);
  const float c00 = v000 * (1.0 - f.x) + v100 * f.x, c10 = v010 * (1.0 - f.x) + v110 * f.x;
  const float c01 = v001 * (1.0 - f.x) + v101 * f.x, c11 = v011 * (1.0 - f.x) + v111 * f.x;
  const float c0 = c00 * (1.0 - f.y) + c10 * f.y, c1 = c01 * (1.0 - f.y) + c11 * f.y;
  gradient = vec3(0.0);
  if (want_gradient) {
    const float gx = ((v100 - v000) * (1.0 - f.y) + (v110 - v010) * f.y) * (1.0 - f.z) +
                     ((v101 - v001) * (1.0 - f.y) + (v111 - v011) * f.y) * f.z;
    const float gy = (c10 - c00) * (1.0 - f.z) + (c11 - c01) * f.z;
    const float gz = c1 - c0;
    gradient = vec3(inside.x ? gx : 0.0, inside.y ? gy : 0.0, inside.z ? gz : 0.0) / pc.spacing;
  }
  return c0 * (1.0 - f.z) + c1 * f.z;
}

#endif
