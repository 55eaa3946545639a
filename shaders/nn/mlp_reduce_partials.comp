#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// grad (+)= sum over slabs of partials[slab][p]: the second half of the atomic-free parameter
// gradient. Each slab's copy holds a layer's weights [out][in_stride] then its biases [out], and
// copies lie slab_stride4 vec4 apart; in the gradient array they go to the layer's weight and
// bias offsets. An invocation sums one vec4 of the copies by texel fetch (a gather on lavapipe,
// where a storage-buffer load loops over the lanes and checks bounds per component).

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) buffer Grads { float grads[]; };  // the whole parameter-gradient array
layout(binding = 16) uniform samplerBuffer partials;          // [slab][slab_stride4]

layout(push_constant) uniform Push {
  uint weights;  // out * in_stride
  uint biases;   // out
  uint slabs;
  uint weight_offset;
  uint bias_offset;
  uint accumulate;
  uint slab_stride4;
} pc;

void main() {
  const uint p4 = nf_linear_index();
  const uint layer_params = pc.weights + pc.biases;
  if (4u * p4 >= layer_params) return;
  vec4 sum = vec4(0.0);
  for (uint sl = 0u; sl < pc.slabs; ++sl) sum += texelFetch(partials, int(sl * pc.slab_stride4 + p4));
  [[unroll]] for (uint e = 0u; e < 4u; ++e) {
    const uint p = 4u * p4 + e;
    if (p >= layer_params) break;
    const uint g = p < pc.weights ? pc.weight_offset + p : pc.bias_offset + (p - pc.weights);
    grads[g] = pc.accumulate != 0u ? grads[g] + sum[e] : sum[e];
  }
}
