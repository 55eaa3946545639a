// Shared by the radix-sort kernels: 4-bit digits, 16 bins, per-invocation bin counts packed as
// 16-bit fields into two uvec4 (bins 0-7 in `lo`, 8-15 in `hi`) so one workgroup scan ranks all bins.
#ifndef NF_RADIX_GLSL
#define NF_RADIX_GLSL

const uint NF_RADIX_BINS = 16u;

uint nf_radix_digit(uint key, uint shift) { return (key >> shift) & 15u; }

// Adds one to `bin` in the packed counters. Branch-free and without dynamic vector indexing: on
// SIMD CPUs (lavapipe) both would serialise the lanes.
void nf_radix_count(uint bin, inout uvec4 lo, inout uvec4 hi) {
  const uvec4 word = uvec4(equal(uvec4(0u, 1u, 2u, 3u), uvec4((bin >> 1) & 3u)));
  const uvec4 one = word << ((bin & 1u) * 16u);
  const uint upper = bin >> 3;  // 0 for bins 0-7, 1 for 8-15
  lo += one * (1u - upper);
  hi += one * upper;
}

uint nf_radix_field(uint bin, uvec4 lo, uvec4 hi) {
  const uvec4 v = (bin >> 3) != 0u ? hi : lo;
  const uvec4 word = uvec4(equal(uvec4(0u, 1u, 2u, 3u), uvec4((bin >> 1) & 3u)));
  const uint packed = v.x * word.x + v.y * word.y + v.z * word.z + v.w * word.w;
  return (packed >> ((bin & 1u) * 16u)) & 0xffffu;
}

#endif
