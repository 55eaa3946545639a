#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// Roofline probe: fp32 FMA rate. Sixteen independent vec4 accumulator chains per invocation keep
// the FMA units busy; the result is stored so the compiler cannot drop the work. The loop body is
// unrolled 32 times inside a do-while: on lavapipe each loop iteration costs a mask update and a
// select per live variable, which with one FMA per chain and iteration halved the measured rate
// (57 GFLOP/s against 129 on the 2-core reference machine).

layout(constant_id = 0) const uint WG = 256;
const uint kUnroll = 32u;  // iterations (a multiple of it) per loop trip
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
  vec4 x8 = x0 + 8.0, x9 = x0 + 9.0, x10 = x0 + 10.0, x11 = x0 + 11.0;
  vec4 x12 = x0 + 12.0, x13 = x0 + 13.0, x14 = x0 + 14.0, x15 = x0 + 15.0;
  const vec4 a = vec4(pc.a), b = vec4(pc.b);
  uint k = 0u;
  do {
    [[unroll]] for (uint u = 0u; u < kUnroll; ++u) {
      x0 = fma(x0, a, b); x1 = fma(x1, a, b); x2 = fma(x2, a, b); x3 = fma(x3, a, b);
      x4 = fma(x4, a, b); x5 = fma(x5, a, b); x6 = fma(x6, a, b); x7 = fma(x7, a, b);
      x8 = fma(x8, a, b); x9 = fma(x9, a, b); x10 = fma(x10, a, b); x11 = fma(x11, a, b);
      x12 = fma(x12, a, b); x13 = fma(x13, a, b); x14 = fma(x14, a, b); x15 = fma(x15, a, b);
    }
  } while ((k += kUnroll) < pc.iterations);
  sink[i] = x0 + x1 + x2 + x3 + x4 + x5 + x6 + x7 + x8 + x9 + x10 + x11 + x12 + x13 + x14 + x15;
}
