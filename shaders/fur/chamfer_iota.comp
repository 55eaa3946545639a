#version 460
#extension GL_GOOGLE_include_directive : require
// values[i] = i: the query indices sorted along with their nearest points. Host wrapper:
// engine/fur/strand_chamfer.cpp.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) writeonly buffer Values { uint values[]; };

layout(push_constant) uniform Push {
  uint count;
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i < pc.count) values[i] = i;
}
