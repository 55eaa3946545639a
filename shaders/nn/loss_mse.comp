#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// Mean squared error over the first `dims` columns of [batch][stride] rows: writes dL/dy (zero on
// padding) and per-workgroup partial sums of the loss. L = sum (y - t)^2 / (batch * dims).
// An invocation takes one vec4 of a row: the prediction by texel fetch and the gradient as one
// vec4 store (on lavapipe every storage access loops over the lanes, so fewer and wider ones).
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) writeonly buffer Grad { vec4 grad[]; };  // [batch][stride4]
layout(std430, binding = 1) readonly buffer Target { float t[]; };   // [batch][dims]
layout(std430, binding = 2) writeonly buffer Partials { float partials[]; };
layout(binding = 16) uniform samplerBuffer y;                         // [batch][stride4]

layout(push_constant) uniform Push {
  uint batch;
  uint dims;
  uint stride4;
} pc;

shared float sums[WG];

void main() {
  const uint count4 = pc.batch * pc.stride4;
  if (nf_linear_group() * WG >= count4) return;  // groups folded past the end
  const uint i = nf_linear_index();
  float loss = 0.0;
  if (i < count4) {
    const uint s = i / pc.stride4, first = 4u * (i % pc.stride4);
    const vec4 yv = texelFetch(y, int(i));
    vec4 g = vec4(0.0);
    [[unroll]] for (uint e = 0u; e < 4u; ++e) {
      if (first + e < pc.dims) {
        const float r = yv[e] - t[s * pc.dims + first + e];
        loss += r * r;
        g[e] = 2.0 * r / float(pc.batch * pc.dims);
      }
    }
    grad[i] = g;
  }
  const float total = subgroupAdd(loss);
  if (subgroupElect()) sums[gl_SubgroupID] = total;
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    float sum = 0.0;
    for (uint k = 0u; k < gl_NumSubgroups; ++k) sum += sums[k];
    partials[nf_linear_group()] = sum / float(max(1u, pc.batch * pc.dims));
  }
}
