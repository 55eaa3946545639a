#version 460
#extension GL_GOOGLE_include_directive : require
// Multiresolution hash-grid encoding (instant-ngp), forward: one sample per invocation, all levels.
// Host: engine/nn/hash_grid.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_hash_grid.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };    // [batch][3]
layout(std430, binding = 1) readonly buffer Table { float table[]; };      // [levels][T][features]
layout(std430, binding = 2) writeonly buffer Encoded { float encoded[]; }; // [batch][out_stride]

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.batch) return;
  const vec3 x = vec3(points[3u * s], points[3u * s + 1u], points[3u * s + 2u]);
  const uint table_size = 1u << pc.log2_table;
  for (uint l = 0u; l < pc.levels; ++l) {
    uvec3 cell;
    vec3 frac;
    nf_hash_grid_cell(x, pc.resolution[l], cell, frac);
    vec4 acc = vec4(0.0);
    for (uint corner = 0u; corner < 8u; ++corner) {
      const uvec3 up = uvec3(corner & 1u, (corner >> 1) & 1u, (corner >> 2) & 1u);
      const vec3 wa = mix(1.0 - frac, frac, vec3(up));
      const float w = wa.x * wa.y * wa.z;
      const uint e = (l * table_size + nf_hash_grid_index(l, cell + up)) * pc.features;
      for (uint f = 0u; f < pc.features; ++f) acc[f] += w * table[e + f];
    }
    for (uint f = 0u; f < pc.features; ++f) encoded[s * pc.out_stride + pc.out_offset + l * pc.features + f] = acc[f];
  }
  for (uint i = pc.out_offset + pc.levels * pc.features; i < pc.out_stride; ++i) encoded[s * pc.out_stride + i] = 0.0;
}
