#version 460
#extension GL_GOOGLE_include_directive : require
// Hash-grid adjoint: dL/dtable by float atomics, and optionally dL/dpoints. On dense (coarse)
// levels many lanes hit the same vertex, so lanes with equal entries are summed in the subgroup
// first and one lane adds the sum; hashed levels rarely collide and add directly.
#extension GL_EXT_shader_atomic_float : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_hash_grid.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };      // [batch][3]
layout(std430, binding = 1) readonly buffer Table { float table[]; };
layout(std430, binding = 2) readonly buffer GradEncoded { float grad[]; };   // [batch][out_stride]
layout(std430, binding = 3) buffer GradTable { float grad_table[]; };        // accumulated
layout(std430, binding = 4) buffer GradPoints { float grad_points[]; };      // [batch][3]

void add_to_table(uint e, vec4 value, bool pre_reduce) {
  if (!pre_reduce) {
    for (uint f = 0u; f < pc.features; ++f) atomicAdd(grad_table[e + f], value[f]);
    return;
  }
  for (;;) {  // one distinct entry per round
    const uint leader = subgroupBroadcastFirst(e);
    if (e == leader) {
      const vec4 sum = subgroupAdd(value);
      if (subgroupElect())
        for (uint f = 0u; f < pc.features; ++f) atomicAdd(grad_table[e + f], sum[f]);
      break;
    }
  }
}

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.batch) return;
  const vec3 x = vec3(points[3u * s], points[3u * s + 1u], points[3u * s + 2u]);
  const uint table_size = 1u << pc.log2_table;
  vec3 dx = vec3(0.0);
  for (uint l = 0u; l < pc.levels; ++l) {
    const uint n = pc.resolution[l];
    uvec3 cell;
    vec3 frac;
    nf_hash_grid_cell(x, n, cell, frac);
    vec4 g = vec4(0.0);
    for (uint f = 0u; f < pc.features; ++f) g[f] = grad[s * pc.out_stride + pc.out_offset + l * pc.features + f];
    const bool dense = (pc.dense_mask & (1u << l)) != 0u;
    for (uint corner = 0u; corner < 8u; ++corner) {
      const uvec3 up = uvec3(corner & 1u, (corner >> 1) & 1u, (corner >> 2) & 1u);
      const vec3 wa = mix(1.0 - frac, frac, vec3(up));
      const vec3 sign = mix(vec3(-1.0), vec3(1.0), vec3(up));
      const float w = wa.x * wa.y * wa.z;
      const uint e = (l * table_size + nf_hash_grid_index(l, cell + up)) * pc.features;
      add_to_table(e, w * g, dense);
      if (pc.has_grad_points != 0u) {
        float gt = 0.0;
        for (uint f = 0u; f < pc.features; ++f) gt += g[f] * table[e + f];
        dx += gt * float(n) * sign * vec3(wa.y * wa.z, wa.x * wa.z, wa.x * wa.y);
      }
    }
  }
  if (pc.has_grad_points == 0u) return;
  for (uint a = 0u; a < 3u; ++a) {
    const float d = x[a] >= 0.0 && x[a] <= 1.0 ? dx[a] : 0.0;  // clamped coordinates do not move
    const uint i = 3u * s + a;
    grad_points[i] = pc.accumulate_points != 0u ? grad_points[i] + d : d;
  }
}
