#version 460
#extension GL_GOOGLE_include_directive : require
// Roofline probe: memory bandwidth as kernels see it (vec4 loads and stores, one per invocation).
// Also the smallest useful kernel for dispatch-latency measurements (n = 1).

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Source { vec4 source[]; };
layout(std430, binding = 1) writeonly buffer Destination { vec4 destination[]; };

layout(push_constant) uniform Push { uint n; } pc;

void main() {
  const uint i = nf_linear_index();
  if (i < pc.n) destination[i] = source[i];
}
