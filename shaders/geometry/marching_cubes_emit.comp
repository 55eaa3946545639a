#version 460
#extension GL_GOOGLE_include_directive : require
// Marching cubes, pass 2, one invocation per grid point of a slab of z-layers: writes the vertex of
// each of the point's crossing grid edges (at the index the scan gave the edge) and the triangles of
// the cell whose lowest corner it is (at the cell's scanned offset; indices are the scanned ids of
// the cell's edges). Positions and normals follow engine/geometry/marching_cubes.cpp: linear
// interpolation on the edge (`precise`, the CPU's float operations in its order), and the central-
// difference gradient (one-sided at the border) interpolated the same way, normalised. Every window
// starts `*_shift` elements into its binding. Host wrapper: engine/geometry/marching_cubes_gpu.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Values { float values[]; };          // layers [values_z, z0 + slab + 2)
layout(std430, binding = 1) readonly buffer Table { uint table[]; };            // NF_MC_ROW per case
layout(std430, binding = 2) readonly buffer Edges { uint edge_ids[]; };         // 3 per point, layers [z0, z0 + slab + 1)
layout(std430, binding = 3) readonly buffer Cells { uint first_triangle[]; };   // 1 per point of the slab
layout(std430, binding = 4) writeonly buffer Positions { float positions[]; };  // the slab's vertices, xyz
layout(std430, binding = 5) writeonly buffer Normals { float normals[]; };      // the slab's vertices, xyz
layout(std430, binding = 6) writeonly buffer Triangles { uint out_triangles[]; };  // the slab's triangles

layout(push_constant) uniform Push {
  uint nx;
  uint ny;
  uint nz;
  uint z0;              // the slab's first layer
  uint count;           // points in the slab
  uint values_z;        // the first layer in the values window
  uint values_shift;
  uint edges_shift;
  uint cells_shift;
  uint vertex_base;     // id of the slab's first vertex
  uint vertex_shift;    // in floats, for positions and normals alike
  uint triangle_base;   // index of the slab's first triangle
  uint triangle_shift;  // in uints
  float iso;
  float origin_x;
  float origin_y;
  float origin_z;
  float h_x;
  float h_y;
  float h_z;
} pc;

float mc_value(uvec3 p) { return values[pc.values_shift + ((p.z - pc.values_z) * pc.ny + p.y) * pc.nx + p.x]; }

#include "nf_marching_cubes.glsl"

uint grid_size(uint axis) { return axis == 0u ? pc.nx : (axis == 1u ? pc.ny : pc.nz); }
float grid_step(uint axis) { return axis == 0u ? pc.h_x : (axis == 1u ? pc.h_y : pc.h_z); }

// Gradient at grid point p in world units: central differences, one-sided on the grid's faces
// (every axis has at least 2 samples).
vec3 gradient(uvec3 p) {
  const float c = mc_value(p);
  vec3 g;
  for (uint axis = 0u; axis < 3u; ++axis) {
    uvec3 lo = p, hi = p;
    lo[axis] -= p[axis] > 0u ? 1u : 0u;
    hi[axis] += p[axis] + 1u < grid_size(axis) ? 1u : 0u;
    const float h = grid_step(axis);
    if (p[axis] == 0u)
      g[axis] = (mc_value(hi) - c) / h;
    else if (p[axis] + 1u == grid_size(axis))
      g[axis] = (c - mc_value(lo)) / h;
    else
      g[axis] = (mc_value(hi) - mc_value(lo)) / (2.0 * h);
  }
  return g;
}

// The vertex on the crossing grid edge from a to b = a + 1 along `axis`.
void emit_vertex(uvec3 a, uvec3 b, uint axis, uint id) {
  const float va = mc_value(a), vb = mc_value(b);
  precise float t = (pc.iso - va) / (vb - va);  // vb != va: exactly one of them is below iso
  t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
  precise vec3 grid = vec3(a);
  grid[axis] += t;
  precise vec3 world = vec3(pc.origin_x, pc.origin_y, pc.origin_z) + grid * vec3(pc.h_x, pc.h_y, pc.h_z);

  // The normal's direction only: scaled by the largest component before normalising, so that
  // steep fields do not overflow the length.
  const vec3 g = mix(gradient(a), gradient(b), t);
  const float m = max(max(abs(g.x), abs(g.y)), abs(g.z));
  vec3 n = vec3(0.0);
  if (nf_mc_finite(g.x) && nf_mc_finite(g.y) && nf_mc_finite(g.z) && m > 0.0) {
    n = normalize(g / m);
  } else {
    n[axis] = vb > va ? 1.0 : -1.0;  // flat gradient: the edge's own direction towards outside
  }

  const uint at = pc.vertex_shift + 3u * (id - pc.vertex_base);
  positions[at] = world.x;
  positions[at + 1u] = world.y;
  positions[at + 2u] = world.z;
  normals[at] = n.x;
  normals[at + 1u] = n.y;
  normals[at + 2u] = n.z;
}

// The triangles of the cell whose lowest corner is p (slab point i).
void emit_triangles(uvec3 p, uint i, uint plane) {
  const uint row = NF_MC_ROW * nf_mc_case(p, pc.iso);
  const uint corners = 3u * table[row];
  if (corners == 0u) return;
  const uint at = pc.triangle_shift + 3u * (first_triangle[pc.cells_shift + i] - pc.triangle_base);
  for (uint k = 0u; k < corners; ++k) {
    const uint code = table[row + 1u + k];
    const uvec3 d = nf_mc_corner(code);
    // The edge's low corner as a slab point: the edge window starts at the slab's first layer.
    const uint corner = i + d.x + d.y * pc.nx + d.z * plane;
    out_triangles[at + k] = edge_ids[pc.edges_shift + 3u * corner + nf_mc_axis(code)];
  }
}

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.count) return;
  const uint plane = pc.nx * pc.ny;
  const uint layer = i / plane, rest = i - layer * plane;
  const uvec3 p = uvec3(rest % pc.nx, rest / pc.nx, pc.z0 + layer);

  const bool inside = mc_value(p) < pc.iso;
  for (uint axis = 0u; axis < 3u; ++axis) {
    uvec3 q = p;
    q[axis] += 1u;
    if (q[axis] < grid_size(axis) && (mc_value(q) < pc.iso) != inside)
      emit_vertex(p, q, axis, edge_ids[pc.edges_shift + 3u * i + axis]);
  }
  if (p.x + 1u < pc.nx && p.y + 1u < pc.ny && p.z + 1u < pc.nz) emit_triangles(p, i, plane);
}
