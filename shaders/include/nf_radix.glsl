// Shared by the radix-sort kernels: 4-bit digits, 16 bins, per-invocation bin counts packed as
// 16-bit fields into two uvec4 (bins 0-7 in `lo`, 8-15 in `hi`) so one workgroup scan ranks all bins.
#ifndef NF_RADIX_GLSL
#define NF_RADIX_GLSL

const uint NF_RADIX_BINS = 16u;

uint nf_radix_digit(uint key, uint shift) { return (key >> shift) & 15u; }

// Adds one to `bin` in the packed counters.
void nf_radix_count(uint bin, inout uvec4 lo, inout uvec4 hi) {
  const uint word = (bin >> 1) & 3u, one = 1u << ((bin & 1u) * 16u);
  if (bin < 8u) lo[word] += one; else hi[word] += one;
}

uint nf_radix_field(uint bin, uvec4 lo, uvec4 hi) {
  const uint word = (bin >> 1) & 3u, shift = (bin & 1u) * 16u;
  return ((bin < 8u ? lo[word] : hi[word]) >> shift) & 0xffffu;
}

#endif
