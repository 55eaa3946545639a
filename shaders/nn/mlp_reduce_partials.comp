#version 460
#extension GL_GOOGLE_include_directive : require
// grad (+)= sum over slabs of partials[slab][p]: the second half of the atomic-free parameter
// gradient. Each slab's copy holds a layer's weights [out][in_stride] then its biases [out], and
// copies lie slab_stride floats apart; in the gradient array they go to the layer's weight and
// bias offsets.

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Partials { float partials[]; };
layout(std430, binding = 1) buffer Grads { float grads[]; };  // the whole parameter-gradient array

layout(push_constant) uniform Push {
  uint weights;  // out * in_stride
  uint biases;   // out
  uint slabs;
  uint weight_offset;
  uint bias_offset;
  uint accumulate;
  uint slab_stride;
} pc;

void main() {
  const uint p = nf_linear_index();
  const uint layer_params = pc.weights + pc.biases;
  if (p >= layer_params) return;
  float sum = 0.0;
  for (uint sl = 0u; sl < pc.slabs; ++sl) sum += partials[sl * pc.slab_stride + p];
  const uint g = p < pc.weights ? pc.weight_offset + p : pc.bias_offset + (p - pc.weights);
  grads[g] = pc.accumulate != 0u ? grads[g] + sum : sum;
}
