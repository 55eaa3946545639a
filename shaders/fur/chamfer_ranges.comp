#version 460
#extension GL_GOOGLE_include_directive : require
// The range [start, end) of each key in a sorted key array (the arrays are zero-filled first, so
// absent keys are empty ranges). Host wrapper: engine/fur/strand_chamfer.cpp.

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Keys { uint keys[]; };
layout(std430, binding = 1) buffer Start { uint start[]; };
layout(std430, binding = 2) buffer End { uint end_[]; };

layout(push_constant) uniform Push {
  uint count;
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.count) return;
  const uint key = keys[i];
  if (key == 0xffffffffu) return;  // unmatched queries (the backward's keys) own no range
  if (i == 0u || keys[i - 1u] != key) start[key] = i;
  if (i + 1u == pc.count || keys[i + 1u] != key) end_[key] = i + 1u;
}
