#version 460
#extension GL_GOOGLE_include_directive : require
// Diagnostic: records what each invocation sees of its subgroup, so tests can check the driver's
// subgroup builtins and arithmetic against the assumptions of nf_workgroup.glsl.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) writeonly buffer Probe { uvec4 probe[]; };  // 2 entries per invocation

void main() {
  const uint i = gl_LocalInvocationIndex;
  probe[2 * i] = uvec4(gl_SubgroupID, gl_NumSubgroups, gl_SubgroupSize, gl_SubgroupInvocationID);
  const uint one = 1u;
  probe[2 * i + 1] = uvec4(subgroupInclusiveAdd(one), subgroupAdd(one), subgroupExclusiveAdd(i),
                           subgroupElect() ? 1u : 0u);
}
