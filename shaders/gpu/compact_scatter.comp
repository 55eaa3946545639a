#version 460
#extension GL_GOOGLE_include_directive : require
// Stream compaction, final pass: element i with a non-zero flag goes to out[offsets[i]], where
// offsets is the exclusive scan of the flags. Writes the element's index or its value.

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Flags { uint flags[]; };
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 2) readonly buffer Values { uint values[]; };
layout(std430, binding = 3) writeonly buffer Output { uint result[]; };

layout(push_constant) uniform Push {
  uint n;
  uint has_values;
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.n || flags[i] == 0u) return;
  uint kept = i;
  if (pc.has_values != 0u) kept = values[i];  // a branch, not a select: `values` may be unbound
  result[offsets[i]] = kept;
}
