// Workgroup-wide sums and exclusive prefix sums built from subgroup operations. They work for any
// subgroup size (4, 8, 32, 64...) and for partial subgroups: nothing here assumes a lane count.
// Include after declaring `layout(constant_id = 0) const uint WG` (the workgroup size in x) and the
// GL_KHR_shader_subgroup_basic / _arithmetic extensions. Every invocation must call these in
// uniform control flow (they contain barriers).
#ifndef NF_WORKGROUP_GLSL
#define NF_WORKGROUP_GLSL

// The lanes a subgroup really has. Not gl_SubgroupSize: lavapipe 22.3 at LP_NATIVE_VECTOR_WIDTH=1024
// reports 32 there while running 16-lane subgroups (tests/gpu/test_subgroups.cpp checks this).
// gl_NumSubgroups is right, and WG is a multiple of the subgroup size (the host checks).
uint nf_subgroup_lanes() { return WG / gl_NumSubgroups; }

// The order the scans below follow. Vulkan does not promise that subgroups tile the workgroup in
// gl_LocalInvocationIndex order, so ordered work is assigned by this rank instead. It is a
// bijection onto [0, WG) whenever WG is a multiple of the subgroup size (the host checks).
uint nf_wg_rank() { return gl_SubgroupID * nf_subgroup_lanes() + gl_SubgroupInvocationID; }

shared uvec4 nf_wg_partials[WG];  // one slot per subgroup; WG bounds the subgroup count
shared uvec4 nf_wg_total;

// Exclusive prefix sum of `v` over the workgroup in nf_wg_rank() order; `total` gets the full sum.
uvec4 nf_wg_exclusive_add(uvec4 v, out uvec4 total) {
  const uvec4 inclusive = subgroupInclusiveAdd(v);
  const uvec4 subgroup_sum = subgroupAdd(v);
  if (subgroupElect()) nf_wg_partials[gl_SubgroupID] = subgroup_sum;
  barrier();
  if (gl_SubgroupID == 0) {
    // Scan the per-subgroup sums in chunks of the subgroup size, carrying between chunks.
    uvec4 carry = uvec4(0);
    for (uint first = 0; first < gl_NumSubgroups; first += nf_subgroup_lanes()) {
      const uint i = first + gl_SubgroupInvocationID;
      const uvec4 x = i < gl_NumSubgroups ? nf_wg_partials[i] : uvec4(0);
      const uvec4 x_inclusive = subgroupInclusiveAdd(x);
      if (i < gl_NumSubgroups) nf_wg_partials[i] = carry + x_inclusive - x;
      carry += subgroupAdd(x);
    }
    if (subgroupElect()) nf_wg_total = carry;
  }
  barrier();
  const uvec4 result = nf_wg_partials[gl_SubgroupID] + inclusive - v;
  total = nf_wg_total;
  barrier();  // the shared slots may be reused by the next call
  return result;
}

uint nf_wg_exclusive_add(uint v, out uint total) {
  uvec4 total4;
  const uint result = nf_wg_exclusive_add(uvec4(v, 0, 0, 0), total4).x;
  total = total4.x;
  return result;
}

// Sum over the workgroup, returned to every invocation.
uvec4 nf_wg_add(uvec4 v) {
  const uvec4 subgroup_sum = subgroupAdd(v);
  if (subgroupElect()) nf_wg_partials[gl_SubgroupID] = subgroup_sum;
  barrier();
  if (gl_LocalInvocationIndex == 0) {
    uvec4 sum = uvec4(0);
    for (uint i = 0; i < gl_NumSubgroups; ++i) sum += nf_wg_partials[i];
    nf_wg_total = sum;
  }
  barrier();
  const uvec4 result = nf_wg_total;
  barrier();
  return result;
}

#endif
