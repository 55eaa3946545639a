// Shared by the hash-grid kernels: push constants and the vertex lookup. CPU twin and the maths:
// engine/nn/hash_grid_ref.hpp.
#ifndef NF_HASH_GRID_GLSL
#define NF_HASH_GRID_GLSL

layout(push_constant) uniform Push {
  uint batch;
  uint levels;
  uint features;
  uint log2_table;
  uint out_stride;       // row length of the encoded rows
  uint dense_mask;       // bit l: level l indexes its table directly
  uint has_grad_points;  // backward: also write dL/dpoints
  uint accumulate_points;
  uint resolution[16];
  uint out_offset;  // first column of the encoding in its rows
} pc;

uint nf_hash_grid_index(uint level, uvec3 v) {
  if ((pc.dense_mask & (1u << level)) != 0u) {
    const uint n = pc.resolution[level] + 1u;
    return v.x + v.y * n + v.z * n * n;
  }
  return (v.x * 1u ^ v.y * 2654435761u ^ v.z * 805459861u) & ((1u << pc.log2_table) - 1u);
}

// Cell and fraction of a point at resolution n (points outside [0, 1] are clamped).
void nf_hash_grid_cell(vec3 x, uint n, out uvec3 cell, out vec3 frac) {
  const vec3 p = clamp(x, 0.0, 1.0) * float(n);
  cell = min(uvec3(floor(p)), uvec3(n - 1u));
  frac = p - vec3(cell);
}

#endif
