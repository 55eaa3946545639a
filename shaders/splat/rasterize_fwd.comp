#version 460
#extension GL_GOOGLE_include_directive : require
// Strand rasterisation, pass 4: front-to-back compositing per tile. Writes the 5 channels (alpha,
// orientation x/y, confidence, depth; planar), the final transmittance and how far into the tile's
// list each pixel went (for the backward pass). Gaussians behind the body depth are skipped. How
// Gaussians reach pixels (subgroup batches, ballot, broadcast): nf_splat_composite.glsl.

layout(constant_id = 0) const uint WG = 64;  // NF_TILE^2
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"

layout(std430, binding = 0) readonly buffer Proj { vec4 proj4[]; };  // 3 per Gaussian
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

// Per-pixel compositing state.
float T = 1.0;
vec4 acc = vec4(0.0);  // orientation x, y, confidence, depth
bool done;
uint last_used = 0u;
float occluder;
vec2 q;

void composite(const NfGaussian g, uint position) {
  if (done || g.depth > occluder) return;
  const float alpha = nf_alpha_of(g, nf_power_of(g, q));
  if (alpha <= 0.0) return;
  const float next = T * (1.0 - alpha);
  if (next < T_MIN) {
    done = true;
    return;
  }
  acc += alpha * T * vec4(g.attr, g.depth);
  T = next;
  last_used = position + 1u;
}

void main() {
  const uint tile = nf_linear_group();
  if (tile >= pc.tiles_x * ((pc.height + NF_TILE - 1u) / NF_TILE)) return;  // folded dispatches may overshoot
  const uint ty = tile / pc.tiles_x, tx = tile - ty * pc.tiles_x;
  const uint lx = gl_LocalInvocationID.x % NF_TILE, ly = gl_LocalInvocationID.x / NF_TILE;
  const uint px = tx * NF_TILE + lx, py = ty * NF_TILE + ly;
  const bool inside = px < pc.width && py < pc.height;
  const uint pix = py * pc.width + px;
  occluder = (inside && pc.has_body != 0u) ? body_depth[pix] : 3.0e38;
  q = vec2(px, py) + 0.5;
  vec2 lo, hi;
  nf_subgroup_rect(q, lo, hi);
  const uint start = ranges[2u * tile], end = ranges[2u * tile + 1u];
  const uint lane = gl_SubgroupInvocationID;
  done = !inside;
  for (uint first = start; first < end; first += gl_SubgroupSize) {
    if (subgroupAll(done)) break;
    const uint n = min(gl_SubgroupSize, end - first);
    const NfGaussianLanes mine = nf_load_gaussian(values[first + min(lane, n - 1u)]);
    const uvec4 reach = subgroupBallot(lane < n && nf_reaches(nf_unpack(mine), lo, hi));
    for (uint word = 0u; word * 32u < n; ++word) {
      uint bits = reach[word];
      while (bits != 0u) {  // front to back: lowest list position first
        const uint j = word * 32u + uint(findLSB(bits));
        bits &= bits - 1u;
        composite(nf_broadcast(mine, j), first + j - start);
      }
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
