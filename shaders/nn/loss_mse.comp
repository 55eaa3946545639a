#version 460
#extension GL_GOOGLE_include_directive : require
// Mean squared error over the first `dims` columns of [batch][stride] rows: writes dL/dy (zero on
// padding) and per-workgroup partial sums of the loss. L = sum (y - t)^2 / (batch * dims).
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Prediction { float y[]; };  // [batch][stride]
layout(std430, binding = 1) readonly buffer Target { float t[]; };      // [batch][dims]
layout(std430, binding = 2) writeonly buffer Grad { float grad[]; };    // [batch][stride]
layout(std430, binding = 3) writeonly buffer Partials { float partials[]; };

layout(push_constant) uniform Push {
  uint batch;
  uint dims;
  uint stride;
} pc;

shared float sums[WG];

void main() {
  if (nf_linear_group() * WG >= pc.batch * pc.stride) return;  // groups folded past the end
  const uint i = nf_linear_index();
  float loss = 0.0;
  if (i < pc.batch * pc.stride) {
    const uint s = i / pc.stride, d = i % pc.stride;
    float g = 0.0;
    if (d < pc.dims) {
      const float r = y[i] - t[s * pc.dims + d];
      loss = r * r;
      g = 2.0 * r / float(pc.batch * pc.dims);
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
