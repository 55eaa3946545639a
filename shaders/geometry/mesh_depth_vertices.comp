#version 460
#extension GL_GOOGLE_include_directive : require
// Body depth map, pass 1: world -> camera space, one invocation per vertex. The products and sums
// are `precise` and in the order of the CPU reference (engine/geometry/mesh_depth.cpp), so both give
// the same bits. Host wrapper: engine/geometry/mesh_depth.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };  // V * 3, world
layout(std430, binding = 1) writeonly buffer Camera { float cam[]; };         // V * 3, camera space

layout(push_constant) uniform Push {
  vec4 row0;  // rows of the world-to-camera matrix (affine part)
  vec4 row1;
  vec4 row2;
  uint vertices;
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.vertices) return;
  const float x = positions[3u * i], y = positions[3u * i + 1u], z = positions[3u * i + 2u];
  precise float cx = ((pc.row0.x * x + pc.row0.y * y) + pc.row0.z * z) + pc.row0.w;
  precise float cy = ((pc.row1.x * x + pc.row1.y * y) + pc.row1.z * z) + pc.row1.w;
  precise float cz = ((pc.row2.x * x + pc.row2.y * y) + pc.row2.z * z) + pc.row2.w;
  cam[3u * i] = cx;
  cam[3u * i + 1u] = cy;
  cam[3u * i + 2u] = cz;
}
