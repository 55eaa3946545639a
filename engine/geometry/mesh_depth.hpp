#pragma once
// Depth of a triangle mesh at every pixel of a view: the strand splatter's occluder (the furless
// body hides strand Gaussians behind it) and the surface stage's previews (depth, normals, colour).
// Shaders: shaders/geometry/mesh_depth_{vertices,setup,raster}.comp.
//
// Conventions (as io::Camera::project): camera space in OpenGL axes, the camera looks
// down -z, depth = -z_cam; pixel (x, y) covers [x, x+1) x [y, y+1), image y down; depth is sampled
// at pixel centres. The ray of pixel (x, y) is d = ((x + 0.5 - cx) / fx, -(y + 0.5 - cy) / fy, -1)
// in camera space, so a point t * d lies at depth t.
//
// Method: per pixel, the pixel ray is intersected with the triangle's plane (exact and
// perspective-correct: t = (n . v0) / (n . d), n = (v1 - v0) x (v2 - v0)); the pixel is inside the
// triangle when the three signed volumes d . (a x b) over its edges (a, b) share a sign (zero counts
// as inside; either winding; either facing). The edge terms of a shared edge are exact negatives of
// each other, so a closed mesh has no cracks. Depth = min t over the triangles hit with t >= near.
//
// Near plane: a triangle with every vertex closer than `near` is skipped. A triangle crossing the
// near plane is clipped against depth = near (a polygon of up to 4 vertices) only to bound its
// screen box: the pixels tested are the box of the projected clipped polygon, which contains every
// pixel whose ray meets the triangle at t >= near; the per-pixel test then keeps only hits with
// t >= near. Triangles behind the camera never appear; nothing is projected through depth <= 0.
//
// Big triangles: pass 2 (one invocation per triangle) computes the triangle's pixel box (widened by
// a rounding margin of ~1/64 pixel) and, when the box fits one `tile` x `tile` tile, tests its
// pixels at once. A bigger box is cut into tiles (aligned to the box) that become work items: a
// scan over the per-triangle item counts numbers them, and pass 3 runs a fixed grid of invocations
// that stride over all items (each finds its triangle by binary search over the scan). No
// invocation ever tests more than tile^2 pixels per item, and a screen-filling triangle is shared
// among thousands of invocations. Triangles are processed in chunks small enough that the item
// count fits 32 bits and every array fits a storage-buffer binding.
//
// Depth is written with atomicMin on the float's bits as uint (order-preserving for positive
// floats; a plain load first skips most losing candidates); empty pixels keep +inf. GPU and CPU
// reference use the same float operations in the same order (`precise` in GLSL: no FMA
// contraction), so on lavapipe they agree bit for bit (tested); a GPU whose division is not
// correctly rounded may differ in the last bits of a depth.
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "engine/gpu/buffer.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/stream.hpp"

namespace nf::geometry {

inline constexpr float kNoDepth = std::numeric_limits<float>::infinity();

struct DepthCamera {
  glm::mat4 world_to_camera{1.0f};  // OpenGL axes: the camera looks down -z
  float fx = 1, fy = 1, cx = 0, cy = 0;
  std::uint32_t width = 0, height = 0;
  float near = 0.01f;               // scene units; hits closer than this are ignored
};

// From a scene camera (io::Camera or anything with its fields): its camera-to-world pose inverted
// in double, then rounded to float.
template <class Camera>
DepthCamera depth_camera(const Camera& camera, float near = 0.01f) {
  DepthCamera c;
  c.world_to_camera = glm::mat4(glm::inverse(camera.camera_to_world));
  c.fx = float(camera.fx), c.fy = float(camera.fy), c.cx = float(camera.cx), c.cy = float(camera.cy);
  c.width = camera.width, c.height = camera.height;
  c.near = near;
  return c;
}

struct MeshDepthOptions {
  std::uint32_t tile = 8;  // tile side in pixels: the most pixels one work item tests is tile^2
};

// Throws InputError naming the field (size, focal lengths, near plane, matrix) when the camera is
// unusable, and DeviceError when the image exceeds a storage-buffer binding.
void validate(const DepthCamera& camera);

// Records the depth map of the mesh into `depth` (width * height floats, row-major from the top-left;
// kNoDepth where no triangle covers the pixel centre). positions: vertex_count * 3 floats (world),
// triangles: triangle_count * 3 uint32 (trusted: indices < vertex_count, finite positions; the host
// overload checks). The vertex array must fit one storage-buffer binding (DeviceError otherwise).
void mesh_depth(gpu::Stream& stream, const DepthCamera& camera, gpu::BufferRange positions,
                std::uint64_t vertex_count, gpu::BufferRange triangles, std::uint64_t triangle_count,
                gpu::BufferRange depth, const MeshDepthOptions& options = {});

// Host convenience (upload, run, download). Rejects NaN/Inf positions and out-of-range indices
// with an InputError naming the input and the element.
std::vector<float> mesh_depth(gpu::Context& context, const DepthCamera& camera, std::span<const float> positions,
                              std::span<const std::uint32_t> triangles, const MeshDepthOptions& options = {});

// CPU reference: the same maths in straight loops (every triangle, every pixel of its box).
std::vector<float> mesh_depth_ref(const DepthCamera& camera, std::span<const float> positions,
                                  std::span<const std::uint32_t> triangles);

}  // namespace nf::geometry
