#version 460
#extension GL_GOOGLE_include_directive : require
// Roofline probe: fp32 FMA rate. Eight independent vec4 accumulator chains per invocation keep the
// FMA units busy; the result is stored so the compiler cannot drop the work.

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) writeonly buffer Sink { vec4 sink[]; };

layout(push_constant) uniform Push {
  uint iterations;
  float a;  // ~1, from the host so nothing folds at compile time
  float b;
} pc;

void main() {
  const uint i = nf_linear_index();
  vec4 x0 = vec4(float(i)), x1 = x0 + 1.0, x2 = x0 + 2.0, x3 = x0 + 3.0;
  vec4 x4 = x0 + 4.0, x5 = x0 + 5.0, x6 = x0 + 6.0, x7 = x0 + 7.0;
  const vec4 a = vec4(pc.a), b = vec4(pc.b);
  for (uint k = 0u; k < pc.iterations; ++k) {
    x0 = fma(x0, a, b); x1 = fma(x1, a, b); x2 = fma(x2, a, b); x3 = fma(x3, a, b);
    x4 = fma(x4, a, b); x5 = fma(x5, a, b); x6 = fma(x6, a, b); x7 = fma(x7, a, b);
  }
  sink[i] = x0 + x1 + x2 + x3 + x4 + x5 + x6 + x7;
}
