// Linear workgroup and invocation indices for dispatches whose groups Stream::dispatch may have
// folded from x into y (when x alone would exceed maxComputeWorkGroupCount[0]).
// Include after `layout(constant_id = 0) const uint WG` and `layout(local_size_x_id = 0) in;`:
// glslang folds gl_WorkGroupSize at its point of use, so a use above the layout line reads 1.
#ifndef NF_INDEX_GLSL
#define NF_INDEX_GLSL

uint nf_linear_group() { return gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x; }
uint nf_linear_index() { return nf_linear_group() * WG + gl_LocalInvocationID.x; }

#endif
