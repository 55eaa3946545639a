#version 460
#extension GL_GOOGLE_include_directive : require
// Exclusive scan, pass 2 of 2: scans each block of WG*ITEMS elements and adds the block's offset
// (the scanned block sums) and an optional carry from earlier chunks. The last block writes the
// grand total. In-place use (input and output the same range) is allowed: every element is read
// into shared memory before any is written.
//! variant add
//! variant flags -DNF_SCAN_FLAGS
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(constant_id = 0) const uint WG = 256;
layout(constant_id = 1) const uint ITEMS = 4;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_workgroup.glsl"

layout(std430, binding = 0) readonly buffer Input { uint data[]; };
layout(std430, binding = 1) writeonly buffer Output { uint result[]; };
layout(std430, binding = 2) readonly buffer BlockOffsets { uint block_offsets[]; };
layout(std430, binding = 3) readonly buffer Carry { uint carry[]; };
layout(std430, binding = 4) writeonly buffer Total { uint total_out[]; };

layout(push_constant) uniform Push {
  uint n;
  uint has_block_offsets;
  uint has_carry;
  uint has_total;
} pc;

shared uint tile[WG * ITEMS];

void main() {
  const uint block = nf_linear_group();
  const uint base = block * WG * ITEMS;
  if (base >= pc.n) return;
  const uint t = gl_LocalInvocationID.x;
  // Coalesced load into shared memory, then each invocation scans ITEMS consecutive elements.
  for (uint k = 0; k < ITEMS; ++k) {
    const uint i = base + k * WG + t;
    uint v = i < pc.n ? data[i] : 0u;
#ifdef NF_SCAN_FLAGS
    v = v != 0u ? 1u : 0u;
#endif
    tile[k * WG + t] = v;
  }
  barrier();
  const uint r = nf_wg_rank();
  uint running = 0u;
  for (uint k = 0; k < ITEMS; ++k) {
    const uint v = tile[r * ITEMS + k];
    tile[r * ITEMS + k] = running;
    running += v;
  }
  uint block_total;
  const uint prefix = nf_wg_exclusive_add(running, block_total);  // contains barriers
  uint offset = prefix;
  if (pc.has_block_offsets != 0u) offset += block_offsets[block];
  if (pc.has_carry != 0u) offset += carry[0];
  for (uint k = 0; k < ITEMS; ++k) tile[r * ITEMS + k] += offset;
  barrier();
  for (uint k = 0; k < ITEMS; ++k) {
    const uint i = base + k * WG + t;
    if (i < pc.n) result[i] = tile[k * WG + t];
  }
  if (pc.has_total != 0u && t == 0 && base + WG * ITEMS >= pc.n) {
    uint grand = block_total;
    if (pc.has_block_offsets != 0u) grand += block_offsets[block];
    if (pc.has_carry != 0u) grand += carry[0];
    total_out[0] = grand;
  }
}
