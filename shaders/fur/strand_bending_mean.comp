#version 460
#extension GL_GOOGLE_include_directive : require
// The batch's mean bending angle at each position along the strand, in two stages so that no
// invocation loops more than `chunk` times (lavapipe cuts loops of more than 65,535 iterations
// short, measured): stage 0 sums each chunk of strands per position, stage 1 sums the chunks per
// position and divides. Sums run in order (deterministic). Maths: engine/fur/strand_losses_ref.hpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Theta { float theta[]; };      // strands * bends
layout(std430, binding = 1) buffer Partial { float partial[]; };           // chunks * bends
layout(std430, binding = 2) writeonly buffer Mean { float mean_theta[]; };  // bends

layout(push_constant) uniform Push {
  uint strands;
  uint bends;
  uint chunk;  // strands per chunk
  uint stage;
} pc;

void main() {
  const uint id = nf_linear_index();
  const uint chunks = (pc.strands + pc.chunk - 1u) / pc.chunk;
  if (pc.stage == 0u) {
    if (id >= chunks * pc.bends) return;
    const uint c = id / pc.bends, m = id - c * pc.bends;
    const uint end = min(pc.strands, (c + 1u) * pc.chunk);
    float sum = 0.0;
    for (uint i = c * pc.chunk; i < end; ++i) sum += theta[i * pc.bends + m];
    partial[id] = sum;
  } else {
    if (id >= pc.bends) return;
    float sum = 0.0;
    for (uint c = 0u; c < chunks; ++c) sum += partial[c * pc.bends + id];
    mean_theta[id] = sum / float(pc.strands);
  }
}
