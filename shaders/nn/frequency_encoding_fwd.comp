#version 460
#extension GL_GOOGLE_include_directive : require
// Frequency (positional) encoding: for a point x of `dims` coordinates, the row
//   [x, sin(2^0 x), cos(2^0 x), sin(2^1 x), cos(2^1 x), ..., cos(2^(L-1) x)]
// (each term a block of `dims`), padded with zeros to the MLP's row stride. One sample per
// invocation, written four features at a time. Host: engine/nn/frequency_encoding.cpp.

layout(constant_id = 0) const uint WG = 64;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_sincos.glsl"

layout(std430, binding = 0) readonly buffer Points { float points[]; };  // [batch][dims]
layout(std430, binding = 1) writeonly buffer Encoded { vec4 encoded[]; }; // [batch][out4]

layout(push_constant) uniform Push {
  uint batch;
  uint dims;
  uint frequencies;
  uint include_input;
  uint out_dim;
  uint out4;
} pc;

float feature(uint s, uint i) {
  if (i >= pc.out_dim) return 0.0;
  if (pc.include_input != 0u) {
    if (i < pc.dims) return points[s * pc.dims + i];
    i -= pc.dims;
  }
  const uint level = i / (2u * pc.dims), r = i % (2u * pc.dims);
  const uint d = r % pc.dims;
  const float t = nf_reduce_two_pi(ldexp(points[s * pc.dims + d], int(level)));  // 2^level x is exact
  return r < pc.dims ? sin(t) : cos(t);
}

void main() {
  const uint s = nf_linear_index();
  if (s >= pc.batch) return;
  for (uint j = 0u; j < pc.out4; ++j)
    encoded[s * pc.out4 + j] = vec4(feature(s, 4u * j), feature(s, 4u * j + 1u), feature(s, 4u * j + 2u),
                                    feature(s, 4u * j + 3u));
}
