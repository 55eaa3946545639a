#version 460
#extension GL_GOOGLE_include_directive : require
// Reduction (sum, min, max) of float, uint or int: each workgroup reduces a contiguous slice into
// one partial; the host runs the kernel again on the partials with a single workgroup.
//! variant sum_f32 -DOP_SUM -DT=float -DKIND_F32
//! variant min_f32 -DOP_MIN -DT=float -DKIND_F32
//! variant max_f32 -DOP_MAX -DT=float -DKIND_F32
//! variant sum_u32 -DOP_SUM -DT=uint -DKIND_U32
//! variant min_u32 -DOP_MIN -DT=uint -DKIND_U32
//! variant max_u32 -DOP_MAX -DT=uint -DKIND_U32
//! variant sum_i32 -DOP_SUM -DT=int -DKIND_I32
//! variant min_i32 -DOP_MIN -DT=int -DKIND_I32
//! variant max_i32 -DOP_MAX -DT=int -DKIND_I32
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Input { T data[]; };
layout(std430, binding = 1) writeonly buffer Partials { T partials[]; };

layout(push_constant) uniform Push {
  uint n;           // elements in this binding
  uint per_group;   // elements each workgroup reduces
  uint out_offset;  // first partial slot written by this dispatch (chunked inputs)
} pc;

#if defined(OP_SUM)
#define COMBINE(a, b) ((a) + (b))
#define SUBGROUP_OP subgroupAdd
#elif defined(OP_MIN)
#define COMBINE(a, b) min(a, b)
#define SUBGROUP_OP subgroupMin
#else
#define COMBINE(a, b) max(a, b)
#define SUBGROUP_OP subgroupMax
#endif

T identity() {
#if defined(OP_SUM)
  return T(0);
#elif defined(KIND_F32) && defined(OP_MIN)
  return uintBitsToFloat(0x7f800000u);
#elif defined(KIND_F32)
  return uintBitsToFloat(0xff800000u);
#elif defined(KIND_U32) && defined(OP_MIN)
  return 0xffffffffu;
#elif defined(KIND_U32)
  return 0u;
#elif defined(OP_MIN)
  return 0x7fffffff;
#else
  return int(0x80000000u);
#endif
}

shared T group_partials[WG];

void main() {
  const uint group = nf_linear_group();
  const uint begin = group * pc.per_group;
  const uint end = min(pc.n, begin + pc.per_group);
  if (begin >= pc.n && group > 0) return;  // folded tail groups; group 0 always writes (n may be 0)
  T acc = identity();
  for (uint i = begin + gl_LocalInvocationID.x; i < end; i += WG) acc = COMBINE(acc, data[i]);
  acc = SUBGROUP_OP(acc);
  if (subgroupElect()) group_partials[gl_SubgroupID] = acc;
  barrier();
  if (gl_LocalInvocationIndex == 0) {
    T result = identity();
    for (uint s = 0; s < gl_NumSubgroups; ++s) result = COMBINE(result, group_partials[s]);
    partials[pc.out_offset + group] = result;
  }
}
