#version 460
#extension GL_GOOGLE_include_directive : require
// Difference-of-Gaussians prefilter of the Gabor orientation maps, as two separable passes over a
// band of image rows: `rows` blurs each row with both Gaussians, `columns` blurs the columns and
// subtracts (low - high). One invocation per pixel; edges clamp. Filters: engine/orient/gabor_bank.hpp.
// Host: engine/orient/dog_prefilter.cpp.
//! variant rows -DNF_DOG_ROWS
//! variant columns -DNF_DOG_COLUMNS

layout(constant_id = 0) const uint WG = 128;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

// Half taps of both Gaussians: low[0..low_radius] then high[0..high_radius]; tap k weighs +-k.
layout(std430, binding = 0) readonly buffer Taps { float taps[]; };
#ifdef NF_DOG_ROWS
layout(std430, binding = 1) readonly buffer Grey { float grey[]; };    // width * rows
layout(std430, binding = 2) writeonly buffer Low { float low[]; };     // width * rows
layout(std430, binding = 3) writeonly buffer High { float high[]; };   // width * rows
#else
layout(std430, binding = 1) readonly buffer Low { float low[]; };
layout(std430, binding = 2) readonly buffer High { float high[]; };
layout(std430, binding = 3) writeonly buffer Dog { float dog[]; };     // width * rows
#endif

layout(push_constant) uniform Push {
  uint width;
  uint rows;
  uint low_radius;
  uint high_radius;
  uint has_high;  // 0: nothing is subtracted (dog = low-pass only)
} pc;

#ifdef NF_DOG_ROWS
#define SAMPLE(arr, x, y, dx) arr[(y) * int(pc.width) + clamp((x) + (dx), 0, int(pc.width) - 1)]
#else
#define SAMPLE(arr, x, y, dy) arr[clamp((y) + (dy), 0, int(pc.rows) - 1) * int(pc.width) + (x)]
#endif

void main() {
  const uint g = nf_linear_index();
  if (g >= pc.width * pc.rows) return;
  const int y = int(g / pc.width), x = int(g - uint(y) * pc.width);
#ifdef NF_DOG_ROWS
  float l = taps[0] * SAMPLE(grey, x, y, 0);
  for (int k = 1; k <= int(pc.low_radius); ++k) l += taps[k] * (SAMPLE(grey, x, y, -k) + SAMPLE(grey, x, y, k));
  low[g] = l;
  if (pc.has_high != 0u) {
    const uint base = pc.low_radius + 1u;
    float h = taps[base] * SAMPLE(grey, x, y, 0);
    for (int k = 1; k <= int(pc.high_radius); ++k)
      h += taps[base + uint(k)] * (SAMPLE(grey, x, y, -k) + SAMPLE(grey, x, y, k));
    high[g] = h;
  }
#else
  float l = taps[0] * SAMPLE(low, x, y, 0);
  for (int k = 1; k <= int(pc.low_radius); ++k) l += taps[k] * (SAMPLE(low, x, y, -k) + SAMPLE(low, x, y, k));
  float h = 0.0;
  if (pc.has_high != 0u) {
    const uint base = pc.low_radius + 1u;
    h = taps[base] * SAMPLE(high, x, y, 0);
    for (int k = 1; k <= int(pc.high_radius); ++k)
      h += taps[base + uint(k)] * (SAMPLE(high, x, y, -k) + SAMPLE(high, x, y, k));
  }
  dog[g] = l - h;
#endif
}
