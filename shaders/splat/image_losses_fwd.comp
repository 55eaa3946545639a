#version 460
#extension GL_GOOGLE_include_directive : require
// Image-space losses of strand splatting, forward. Two passes (variants):
//   pixels: each workgroup reduces a contiguous slice of pixels to one vec4 partial
//           (sum weight |alpha - mask|, sum w_p term_p, sum weight, sum weight * confidence);
//   finish: one workgroup sums the partials and writes losses = (L_sil, L_dir, N_sil, N_dir).
// Bindings start on the device's offset alignment; pc.shift[b] is where binding b's data begins
// (in floats), so planes of a larger image (the rasteriser's) bind at any pixel count.
// Host wrapper: engine/splat/image_losses.cpp; maths: engine/splat/image_losses_ref.hpp.
//! variant pixels -DPASS_PIXELS
//! variant finish -DPASS_FINISH
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require

layout(constant_id = 0) const uint WG = 256;
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_image_losses.glsl"

shared vec4 sums[WG];

// Sum of v over the workgroup, valid in invocation 0. Call in uniform control flow.
vec4 workgroup_sum(vec4 v) {
  const vec4 s = subgroupAdd(v);
  if (subgroupElect()) sums[gl_SubgroupID] = s;
  barrier();
  vec4 total = vec4(0.0);
  if (gl_LocalInvocationIndex == 0u)
    for (uint k = 0u; k < gl_NumSubgroups; ++k) total += sums[k];
  return total;
}

#if defined(PASS_PIXELS)

layout(std430, binding = 0) readonly buffer Alpha { float alpha[]; };
layout(std430, binding = 1) readonly buffer OrientationX { float orientation_x[]; };
layout(std430, binding = 2) readonly buffer OrientationY { float orientation_y[]; };
layout(std430, binding = 3) readonly buffer Tau { float tau[]; };
layout(std430, binding = 4) readonly buffer Mask { float mask[]; };
layout(std430, binding = 5) readonly buffer Weight { float weight[]; };
layout(std430, binding = 6) readonly buffer GaborAngle { float gabor_angle[]; };
layout(std430, binding = 7) readonly buffer GaborConfidence { float gabor_confidence[]; };
layout(std430, binding = 8) writeonly buffer Partials { vec4 partials[]; };

layout(push_constant) uniform Push {
  uint n;           // pixels in this chunk
  uint per_group;   // pixels each workgroup reduces
  uint out_offset;  // first partial written by this dispatch
  float tau_floor;
  float omin2;      // orientation_min^2
  uint shift[8];    // bindings 0..7
} pc;

void main() {
  const uint group = nf_linear_group();
  const uint begin = group * pc.per_group;
  const uint end = min(pc.n, begin + pc.per_group);
  vec4 acc = vec4(0.0);
  for (uint i = begin + gl_LocalInvocationID.x; i < end; i += WG) {
    const float wt = weight[pc.shift[5] + i];
    if (!(wt > 0.0)) continue;  // bald or off-region pixel: nothing else is read
    acc.x += wt * abs(alpha[pc.shift[0] + i] - mask[pc.shift[4] + i]);
    acc.z += wt;
    const float w = wt * gabor_confidence[pc.shift[7] + i];
    if (!(w > 0.0)) continue;
    acc.w += w;
    const vec2 o = vec2(orientation_x[pc.shift[1] + i], orientation_y[pc.shift[2] + i]);
    float term, dmin, slope;
    if (nf_image_loss_orientation_term(o, tau[pc.shift[3] + i], gabor_angle[pc.shift[6] + i], pc.tau_floor, pc.omin2,
                                       term, dmin, slope))
      acc.y += w * term;
  }
  const vec4 total = workgroup_sum(acc);
  if (gl_LocalInvocationIndex == 0u) partials[pc.out_offset + group] = total;
}

#elif defined(PASS_FINISH)

layout(std430, binding = 0) readonly buffer Partials { vec4 partials[]; };
layout(std430, binding = 1) writeonly buffer Losses { float losses[]; };

layout(push_constant) uniform Push {
  uint n;  // partials
  float norm_floor;
  uint losses_shift;
} pc;

void main() {
  vec4 acc = vec4(0.0);
  for (uint i = gl_LocalInvocationID.x; i < pc.n; i += WG) acc += partials[i];
  const vec4 total = workgroup_sum(acc);
  if (gl_LocalInvocationIndex == 0u) {
    const float n_sil = max(total.z, pc.norm_floor), n_dir = max(total.w, pc.norm_floor);
    losses[pc.losses_shift] = total.x / n_sil;
    losses[pc.losses_shift + 1u] = total.y / n_dir;
    losses[pc.losses_shift + 2u] = n_sil;
    losses[pc.losses_shift + 3u] = n_dir;
  }
}

#endif
