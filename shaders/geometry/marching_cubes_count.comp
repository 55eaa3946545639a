#version 460
#extension GL_GOOGLE_include_directive : require
// Marching cubes, pass 1, one invocation per grid point of a slab of z-layers: flags the point's
// three grid edges (+x, +y, +z) that cross the iso-value, counts the triangles of the cell whose
// lowest corner it is (0 on the grid's far faces), and keeps the lowest index of a NaN/Inf sample.
// Every window starts `*_shift` elements into its binding (bindings start on the device's offset
// alignment). Host wrapper: engine/geometry/marching_cubes_gpu.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Values { float values[]; };  // layers [values_z, z0 + slab + 1)
layout(std430, binding = 1) readonly buffer Table { uint table[]; };    // NF_MC_ROW per case
layout(std430, binding = 2) writeonly buffer Edges { uint edges[]; };   // 3 per point of the slab
layout(std430, binding = 3) writeonly buffer Cells { uint cells[]; };   // 1 per point of the slab
layout(std430, binding = 4) buffer FirstBad { uint first_bad; };        // grid index, ~0u when none

layout(push_constant) uniform Push {
  uint nx;
  uint ny;
  uint nz;
  uint z0;            // the slab's first layer
  uint count;         // points in the slab
  uint values_z;      // the first layer in the values window
  uint values_shift;
  uint edges_shift;
  uint cells_shift;
  float iso;
} pc;

float mc_value(uvec3 p) { return values[pc.values_shift + ((p.z - pc.values_z) * pc.ny + p.y) * pc.nx + p.x]; }

#include "nf_marching_cubes.glsl"

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.count) return;
  const uint plane = pc.nx * pc.ny;
  const uint layer = i / plane, rest = i - layer * plane;
  const uvec3 p = uvec3(rest % pc.nx, rest / pc.nx, pc.z0 + layer);
  const float v = mc_value(p);
  if (!nf_mc_finite(v)) atomicMin(first_bad, pc.z0 * plane + i);

  const bool inside = v < pc.iso;
  const uvec3 size = uvec3(pc.nx, pc.ny, pc.nz);
  for (uint axis = 0u; axis < 3u; ++axis) {
    uvec3 q = p;
    q[axis] += 1u;
    const bool crosses = q[axis] < size[axis] && (mc_value(q) < pc.iso) != inside;
    edges[pc.edges_shift + 3u * i + axis] = crosses ? 1u : 0u;
  }
  uint cell_triangles = 0u;
  if (p.x + 1u < pc.nx && p.y + 1u < pc.ny && p.z + 1u < pc.nz)
    cell_triangles = table[NF_MC_ROW * nf_mc_case(p, pc.iso)];
  cells[pc.cells_shift + i] = cell_triangles;
}
