#version 460
#extension GL_GOOGLE_include_directive : require
// Radix sort pass, step 2: stable scatter. Each invocation owns ITEMS consecutive keys of the block
// (in nf_wg_rank() order); one workgroup scan of the packed bin counts gives each key its rank
// among equal digits in the block, and the scanned histogram gives the block's base per bin.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "nf_radix.glsl"

layout(constant_id = 0) const uint WG = 128;
layout(constant_id = 1) const uint ITEMS = 8;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_workgroup.glsl"

layout(std430, binding = 0) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = 1) readonly buffer ValuesIn { uint values_in[]; };
layout(std430, binding = 2) readonly buffer Offsets { uint offsets[]; };  // scanned histogram
layout(std430, binding = 3) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = 4) writeonly buffer ValuesOut { uint values_out[]; };

layout(push_constant) uniform Push {
  uint n;
  uint shift;
  uint blocks;
  uint has_values;
} pc;

shared uint bin_base[NF_RADIX_BINS];

void main() {
  const uint block = nf_linear_group();
  if (block >= pc.blocks) return;
  if (gl_LocalInvocationIndex < NF_RADIX_BINS)
    bin_base[gl_LocalInvocationIndex] = offsets[gl_LocalInvocationIndex * pc.blocks + block];
  const uint first = block * WG * ITEMS + nf_wg_rank() * ITEMS;
  const uint last = min(first + ITEMS, pc.n);
  uvec4 lo = uvec4(0), hi = uvec4(0);
  // do-while, not for: on lavapipe a for loop runs one more masked body before it leaves.
  if (first < last) {
    uint i = first;
    do nf_radix_count(nf_radix_digit(keys_in[i], pc.shift), lo, hi);
    while (++i < last);
  }
  uvec4 total_lo, total_hi;
  const uvec4 before_lo = nf_wg_exclusive_add(lo, total_lo);  // barriers also publish bin_base
  const uvec4 before_hi = nf_wg_exclusive_add(hi, total_hi);
  uvec4 seen_lo = uvec4(0), seen_hi = uvec4(0);
  if (first < last) {
    uint i = first;
    do {
      const uint key = keys_in[i];
      const uint d = nf_radix_digit(key, pc.shift);
      const uint position = bin_base[d] + nf_radix_field(d, before_lo, before_hi) + nf_radix_field(d, seen_lo, seen_hi);
      nf_radix_count(d, seen_lo, seen_hi);
      keys_out[position] = key;
      if (pc.has_values != 0u) values_out[position] = values_in[i];
    } while (++i < last);
  }
}
