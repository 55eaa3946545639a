#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, pass 4: front-to-back compositing per tile. Writes the 5 channels (alpha,
// orientation x/y, confidence, depth; planar), the final transmittance and how far into the tile's
// list each pixel went (for the backward pass). Gaussians behind the body depth are skipped.

layout(constant_id = 0) const uint WG = 64;  // NF_TILE^2
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Proj { float proj[]; };
layout(std430, binding = 1) readonly buffer Values { uint values[]; };  // sorted Gaussian ids
layout(std430, binding = 2) readonly buffer Ranges { uint ranges[]; };
layout(std430, binding = 3) readonly buffer Body { float body_depth[]; };  // H * W, or 1 float (none)
layout(std430, binding = 4) writeonly buffer Image { float image[]; };     // 5 planes of H * W
layout(std430, binding = 5) writeonly buffer FinalT { float final_t[]; };
layout(std430, binding = 6) writeonly buffer Last { uint last[]; };

layout(push_constant) uniform Push {
  uint width, height, tiles_x, has_body;
} pc;

#include "nf_splat_composite.glsl"

shared uint s_done;

void main() {
  const uint tile = nf_linear_group();
  if (tile >= pc.tiles_x * ((pc.height + NF_TILE - 1u) / NF_TILE)) return;  // folded dispatches may overshoot
  const uint ty = tile / pc.tiles_x, tx = tile - ty * pc.tiles_x;
  const uint lx = gl_LocalInvocationID.x % NF_TILE, ly = gl_LocalInvocationID.x / NF_TILE;
  const uint px = tx * NF_TILE + lx, py = ty * NF_TILE + ly;
  const bool inside = px < pc.width && py < pc.height;
  const uint pix = py * pc.width + px;
  const float occluder = (inside && pc.has_body != 0u) ? body_depth[pix] : 3.0e38;
  const vec2 q = vec2(px, py) + 0.5;
  const uint start = ranges[2u * tile], end = ranges[2u * tile + 1u];
  bool done = !inside;
  float T = 1.0;
  vec4 acc = vec4(0.0);  // orientation x, y, confidence, depth
  uint last_used = 0u;
  if (gl_LocalInvocationID.x == 0u) s_done = 0u;
  barrier();
  if (done) atomicAdd(s_done, 1u);
  for (uint first = start; first < end; first += BATCH) {
    barrier();
    if (s_done == WG) break;  // uniform: read after the barrier
    const uint n = min(BATCH, end - first);
    if (gl_LocalInvocationID.x < n) nf_stage_gaussian(gl_LocalInvocationID.x, values[first + gl_LocalInvocationID.x]);
    barrier();
    // A loop whose bounds are the same for every invocation: the Gaussian index j stays uniform,
    // so CPU devices (lavapipe) load the staged Gaussian once per SIMD batch instead of gathering.
    for (uint j = 0u; j < n; ++j) {
      if (done || s_mean_opacity[j].w > occluder) continue;
      const float alpha = nf_alpha(j, nf_power(j, q));
      if (alpha <= 0.0) continue;
      const float next = T * (1.0 - alpha);
      if (next < T_MIN) {
        done = true;
        atomicAdd(s_done, 1u);
        continue;
      }
      const float w = alpha * T;
      acc += w * vec4(s_attr[j], s_mean_opacity[j].w);
      T = next;
      last_used = first + j - start + 1u;
    }
  }
  if (!inside) return;
  const uint plane = pc.width * pc.height;
  image[pix] = 1.0 - T;
  image[plane + pix] = acc.x;
  image[2u * plane + pix] = acc.y;
  image[3u * plane + pix] = acc.z;
  image[4u * plane + pix] = acc.w;
  final_t[pix] = T;
  last[pix] = last_used;
}
