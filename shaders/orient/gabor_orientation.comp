#version 460
#extension GL_GOOGLE_include_directive : require
// Gabor orientation and confidence per pixel (maths: engine/orient/gabor_ref.hpp). One workgroup per
// TILE x TILE output pixels: the tile plus an APRON of DoG-filtered pixels is staged in shared
// memory once, then each invocation forms the pair sums D(x+p) + D(x-p) of its PIXELS pixels (the
// filters are even, so this halves the multiply-adds) and runs the whole bank over them, four taps
// per vec4 FMA, each loaded weight serving all PIXELS pixels. Every lane reads the same weight,
// from a uniform buffer where the bank fits one (GPUs broadcast it; on lavapipe, whose storage-buffer
// loads loop over the lanes with a bounds check each, the kernel ran 1.8x faster), else from a
// storage buffer (variant ssbo). The host picks PIXELS: 1 on GPUs, 4 on CPU devices.
// The confidence needs d(theta_i, theta_max), known only after the argmax, so the responses are
// kept in a private array of ORIENTATIONS floats per pixel (720 bytes at 180) and read a second time:
// recomputing them would double the cost, and no response image ever reaches memory.
// Host: engine/orient/gabor_orientation.cpp.
//! variant ubo -DNF_WEIGHTS_UBO
//! variant ssbo

layout(constant_id = 0) const uint WG = 64;            // TILE * TILE / PIXELS
layout(constant_id = 1) const uint TILE = 16;
layout(constant_id = 2) const uint APRON = 7;          // largest |dx|, |dy| of a tap
layout(constant_id = 3) const uint TAPS4 = 21;         // tap pairs / 4, rounded up
layout(constant_id = 4) const uint ORIENTATIONS = 180;
layout(constant_id = 5) const uint PIXELS = 4;         // per invocation
layout(local_size_x_id = 0) in;

const uint SPAN = TILE + 2u * APRON;
shared float tile[SPAN * SPAN];

layout(std430, binding = 0) readonly buffer Dog { float dog[]; };          // width * rows
layout(std430, binding = 1) readonly buffer Offsets { ivec4 offsets[]; };  // [TAPS4] tap offsets in the tile
layout(std430, binding = 2) readonly buffer Mask { uint mask[]; };         // optional; 4 pixels per word
layout(std430, binding = 3) writeonly buffer Orientation { float orientation[]; };  // width * out_rows
layout(std430, binding = 4) writeonly buffer Confidence { float confidence[]; };    // width * out_rows
#ifdef NF_WEIGHTS_UBO
layout(std140, binding = 12) uniform Weights { vec4 weights[ORIENTATIONS * TAPS4]; };  // [ORIENTATIONS][TAPS4]
#else
layout(std430, binding = 5) readonly buffer Weights { vec4 weights[]; };  // [ORIENTATIONS][TAPS4]
#endif

layout(push_constant) uniform Push {
  uint width;
  uint rows;       // rows of the DoG band
  uint row_first;  // band row of the first output row
  uint out_rows;
  uint has_mask;
  float bin;                // pi / ORIENTATIONS
  float inv_distance2_sum;  // 1 / sum_i d(theta_i, theta_0)^2
} pc;

void main() {
  const uint lid = gl_LocalInvocationID.x;
  const int ox = int(gl_WorkGroupID.x * TILE), oy = int(gl_WorkGroupID.y * TILE);
  const int x_first = ox - int(APRON), y_first = int(pc.row_first) + oy - int(APRON);
  for (uint i = lid; i < SPAN * SPAN; i += WG) {  // clamped loads: the edges repeat, as in the reference
    const int sx = clamp(x_first + int(i % SPAN), 0, int(pc.width) - 1);
    const int sy = clamp(y_first + int(i / SPAN), 0, int(pc.rows) - 1);
    tile[i] = dog[sy * int(pc.width) + sx];
  }
  barrier();

  // This invocation's pixels sit at tile positions lid + k WG.
  uint out_index[PIXELS];
  bool live[PIXELS];
  vec4 pair[PIXELS][TAPS4];
  bool any_live = false;
  for (uint k = 0u; k < PIXELS; ++k) {
    const uint q = lid + k * WG, lx = q % TILE, ly = q / TILE;
    const uint x = uint(ox) + lx, y = uint(oy) + ly;
    const bool inside = x < pc.width && y < pc.out_rows;
    const uint p = inside ? y * pc.width + x : 0u;  // never index past the mask
    live[k] = inside && (pc.has_mask == 0u || ((mask[p >> 2u] >> ((p & 3u) * 8u)) & 0xffu) != 0u);
    out_index[k] = p;
    if (inside && !live[k]) {
      orientation[p] = 0.0;
      confidence[p] = 0.0;
    }
    any_live = any_live || live[k];
    // Pair sums; the centre is its own pair (its weight is halved on the host), padding weighs 0.
    const int c = int((ly + APRON) * SPAN + lx + APRON);
    for (uint j = 0u; j < TAPS4; ++j) {
      const ivec4 o = offsets[j];
      pair[k][j] = vec4(tile[c + o.x] + tile[c - o.x], tile[c + o.y] + tile[c - o.y],
                        tile[c + o.z] + tile[c - o.z], tile[c + o.w] + tile[c - o.w]);
    }
  }
  if (!any_live) return;

  float response[PIXELS][ORIENTATIONS];
  float best[PIXELS];
  uint m[PIXELS];
  for (uint k = 0u; k < PIXELS; ++k) {
    best[k] = -1.0;
    m[k] = 0u;
  }
  for (uint t = 0u; t < ORIENTATIONS; ++t) {
    vec4 acc[PIXELS];
    for (uint k = 0u; k < PIXELS; ++k) acc[k] = vec4(0.0);
    const uint base = t * TAPS4;
    for (uint j = 0u; j < TAPS4; ++j) {
      const vec4 w = weights[base + j];
      for (uint k = 0u; k < PIXELS; ++k) acc[k] = fma(w, pair[k][j], acc[k]);
    }
    for (uint k = 0u; k < PIXELS; ++k) {
      const float f = abs((acc[k].x + acc[k].y) + (acc[k].z + acc[k].w));
      response[k][t] = f;
      if (f > best[k]) {  // strict: the first maximum wins, as in the reference
        best[k] = f;
        m[k] = t;
      }
    }
  }
  for (uint k = 0u; k < PIXELS; ++k) {
    if (!live[k]) continue;
    float spread = 0.0;
    for (uint t = 0u; t < ORIENTATIONS; ++t) {
      const uint i = t > m[k] ? t - m[k] : m[k] - t;
      const float e = float(min(i, ORIENTATIONS - i)) * pc.bin * (response[k][t] - best[k]);
      spread += e * e;
    }
    orientation[out_index[k]] = float(m[k]) * pc.bin;
    confidence[out_index[k]] = sqrt(spread * pc.inv_distance2_sum);
  }
}
