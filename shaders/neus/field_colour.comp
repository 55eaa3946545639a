#version 460
#extension GL_GOOGLE_include_directive : require
// The colour network's output activation, a sigmoid, and its adjoint. Forward: rgb = sigmoid(y)
// from rows [n][out_stride] into [n][3]. Backward: dL/dy = dL/drgb rgb (1 - rgb), zero padding.
// Host: engine/neus/neus_field.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Rows { float y[]; };        // [n][out_stride]
layout(std430, binding = 1) buffer Rgb { float rgb[]; };                // [n][3]
layout(std430, binding = 2) readonly buffer GradRgb { float grgb[]; };  // backward: [n][3]
layout(std430, binding = 3) writeonly buffer GradRows { float gy[]; };  // backward: [n][out_stride]

layout(push_constant) uniform Push {
  uint n;
  uint out_stride;
  uint backward;
} pc;

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.n) return;
  if (pc.backward == 0u) {
    for (uint c = 0u; c < 3u; ++c) {
      const float v = y[s * pc.out_stride + c];
      const float e = exp(-abs(v));  // sigmoid without overflow
      rgb[3u * s + c] = v >= 0.0 ? 1.0 / (1.0 + e) : e / (1.0 + e);
    }
    return;
  }
  for (uint c = 0u; c < pc.out_stride; ++c) {
    float g = 0.0;
    if (c < 3u) {
      const float r = rgb[3u * s + c];
      g = grgb[3u * s + c] * r * (1.0 - r);
    }
    gy[s * pc.out_stride + c] = g;
  }
}
