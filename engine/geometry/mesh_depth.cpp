// The CPU reference below repeats the shaders' float operations in the same order; contraction into
// FMA (the default of GCC on targets that have it, e.g. arm64) would change the last bits.
#pragma GCC optimize("fp-contract=off")

#include "engine/geometry/mesh_depth.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/core/error.hpp"
#include "engine/core/finite.hpp"
#include "engine/gpu/chunking.hpp"
#include "engine/gpu/kernel.hpp"
#include "engine/gpu/scan.hpp"

namespace nf::geometry {
namespace {

struct VertexPush {
  float rows[12];
  std::uint32_t vertices;
};
// Mirrors the push block of shaders/include/nf_mesh_depth.glsl.
struct DepthPush {
  float fx, fy, inv_fx, inv_fy, cx, cy, near, margin;
  std::uint32_t width, height, tile, triangles, stride;
};

constexpr std::uint32_t kWorkgroup = 64;
constexpr std::uint32_t kInfBits = 0x7f800000u;  // +inf: above every positive float as uint

std::uint64_t tiles_along(std::uint32_t pixels, std::uint32_t tile) { return (pixels + tile - 1) / tile; }

void check_tile(const MeshDepthOptions& options) {
  if (options.tile < 1 || options.tile > 256)
    throw InputError("body depth: tile is " + std::to_string(options.tile) + "; it must lie in [1, 256]");
}

// ---- the maths shared by the reference and (in GLSL) the shaders ----

struct V3 {
  float x, y, z;
};

V3 to_camera(const DepthCamera& cam, const float* p) {
  const glm::mat4& m = cam.world_to_camera;  // m[column][row]
  V3 c;
  c.x = ((m[0][0] * p[0] + m[1][0] * p[1]) + m[2][0] * p[2]) + m[3][0];
  c.y = ((m[0][1] * p[0] + m[1][1] * p[1]) + m[2][1] * p[2]) + m[3][1];
  c.z = ((m[0][2] * p[0] + m[1][2] * p[1]) + m[2][2] * p[2]) + m[3][2];
  return c;
}

struct Box {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // inclusive; empty when x0 > x1
};

DepthPush depth_push(const DepthCamera& cam, std::uint32_t tile) {
  DepthPush p{};
  p.fx = cam.fx, p.fy = cam.fy, p.cx = cam.cx, p.cy = cam.cy, p.near = cam.near;
  p.inv_fx = float(1.0 / double(cam.fx)), p.inv_fy = float(1.0 / double(cam.fy));
  // Rounding slack of the box: projection and pixel rays agree to a few ulp of the coordinates.
  const double extent = std::max({double(cam.width), double(cam.height), std::abs(double(cam.cx)), std::abs(double(cam.cy))});
  p.margin = float(1.0 / 64.0 + 1e-5 * extent);
  p.width = cam.width, p.height = cam.height, p.tile = tile;
  return p;
}

// The conservative pixel box of the part of the triangle at depth >= near (mesh_depth_setup.comp).
Box setup_box(const DepthPush& pc, const V3 v[3]) {
  float umin = 1e30f, umax = -1e30f, vmin = 1e30f, vmax = -1e30f;
  int n = 0;
  for (int k = 0; k < 3; ++k) {
    const V3 a = v[k], b = v[(k + 1) % 3];
    const float da = -a.z - pc.near, db = -b.z - pc.near;
    for (int j = 0; j < 2; ++j) {
      V3 p;
      if (j == 0) {
        if (!(da >= 0)) continue;
        p = a;
      } else {
        if ((da >= 0) == (db >= 0)) continue;
        const float s = da / (da - db);
        p = {a.x + (b.x - a.x) * s, a.y + (b.y - a.y) * s, a.z + (b.z - a.z) * s};
      }
      const float depth = std::max(-p.z, pc.near);
      const float u = pc.cx + (pc.fx * p.x) / depth, w = pc.cy - (pc.fy * p.y) / depth;
      umin = std::min(umin, u), umax = std::max(umax, u), vmin = std::min(vmin, w), vmax = std::max(vmax, w);
      ++n;
    }
  }
  Box box;
  if (n == 0) return box;
  const float W = float(pc.width), H = float(pc.height);
  box.x0 = std::max(int(std::ceil((std::clamp(umin, -4.0f, W + 4.0f) - 0.5f) - pc.margin)), 0);
  box.x1 = std::min(int(std::floor((std::clamp(umax, -4.0f, W + 4.0f) - 0.5f) + pc.margin)), int(pc.width) - 1);
  box.y0 = std::max(int(std::ceil((std::clamp(vmin, -4.0f, H + 4.0f) - 0.5f) - pc.margin)), 0);
  box.y1 = std::min(int(std::floor((std::clamp(vmax, -4.0f, H + 4.0f) - 0.5f) + pc.margin)), int(pc.height) - 1);
  if (box.x0 > box.x1 || box.y0 > box.y1) box = Box{};
  return box;
}

V3 cross(const V3& a, const V3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// nf_mesh_depth_box of shaders/include/nf_mesh_depth.glsl.
void raster_ref(const DepthPush& pc, const V3 v[3], const Box& box, float* depth) {
  const V3 &a = v[0], &b = v[1], &c = v[2];
  const V3 k0 = cross(a, b), k1 = cross(b, c), k2 = cross(c, a);
  const V3 e1{b.x - a.x, b.y - a.y, b.z - a.z}, e2{c.x - a.x, c.y - a.y, c.z - a.z};
  const V3 n = cross(e1, e2);
  const float num = (n.x * a.x + n.y * a.y) + n.z * a.z;
  for (int y = box.y0; y <= box.y1; ++y) {
    const float dy = -(((float(y) + 0.5f) - pc.cy) * pc.inv_fy);
    for (int x = box.x0; x <= box.x1; ++x) {
      const float dx = ((float(x) + 0.5f) - pc.cx) * pc.inv_fx;
      const float s0 = (dx * k0.x + dy * k0.y) - k0.z;
      const float s1 = (dx * k1.x + dy * k1.y) - k1.z;
      const float s2 = (dx * k2.x + dy * k2.y) - k2.z;
      const bool inside = (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
      if (!inside) continue;
      const float den = (n.x * dx + n.y * dy) - n.z;
      if (den == 0) continue;
      const float t = num / den;
      float& d = depth[std::size_t(y) * pc.width + std::size_t(x)];
      if (t >= pc.near && !std::isinf(t)) d = std::min(d, t);
    }
  }
}

void check_mesh(std::span<const float> positions, std::span<const std::uint32_t> triangles) {
  if (positions.size() % 3)
    throw InputError("body depth: mesh positions hold " + std::to_string(positions.size()) +
                     " floats, not a multiple of 3");
  if (triangles.size() % 3)
    throw InputError("body depth: mesh triangles hold " + std::to_string(triangles.size()) +
                     " indices, not a multiple of 3");
  require_finite(positions, "body depth: mesh positions");
  const std::uint64_t vertices = positions.size() / 3;
  for (std::size_t i = 0; i < triangles.size(); ++i)
    if (triangles[i] >= vertices)
      throw InputError("body depth: triangle " + std::to_string(i / 3) + " uses vertex " +
                       std::to_string(triangles[i]) + " of a mesh with " + std::to_string(vertices) + " vertices");
}

}  // namespace

void validate(const DepthCamera& camera) {
  if (camera.width == 0 || camera.height == 0)
    throw InputError("body depth: camera size is " + std::to_string(camera.width) + "x" +
                     std::to_string(camera.height) + "; both must be positive");
  if (camera.width > (1u << 20) || camera.height > (1u << 20))
    throw InputError("body depth: camera size " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                     " is beyond 2^20 pixels a side");
  if (!(camera.fx > 0) || !(camera.fy > 0) || !std::isfinite(camera.fx) || !std::isfinite(camera.fy))
    throw InputError("body depth: focal lengths fx, fy must be positive and finite, got " + std::to_string(camera.fx) +
                     ", " + std::to_string(camera.fy));
  if (!std::isfinite(camera.cx) || !std::isfinite(camera.cy))
    throw InputError("body depth: principal point cx, cy must be finite");
  if (!(camera.near > 0) || !std::isfinite(camera.near))
    throw InputError("body depth: near must be positive and finite, got " + std::to_string(camera.near));
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(camera.world_to_camera[c][r]))
        throw InputError("body depth: world_to_camera[" + std::to_string(r) + "][" + std::to_string(c) +
                         "] is not finite");
}

void mesh_depth(gpu::Stream& stream, const DepthCamera& camera, gpu::BufferRange positions,
                std::uint64_t vertex_count, gpu::BufferRange triangles, std::uint64_t triangle_count,
                gpu::BufferRange depth, const MeshDepthOptions& options) {
  validate(camera);
  check_tile(options);
  gpu::Context& context = stream.context();
  const std::uint64_t pixels = std::uint64_t(camera.width) * camera.height;
  gpu::require_bytes(depth, pixels * 4, "body depth map");
  gpu::require_bytes(positions, vertex_count * 12, "body depth: mesh positions");
  gpu::require_bytes(triangles, triangle_count * 12, "body depth: mesh triangles");
  const std::uint64_t range = context.info().limits.max_storage_buffer_range;
  if (pixels * 4 > range)
    throw DeviceError("body depth: a " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                      " depth map exceeds the device's storage-buffer range of " + std::to_string(range) + " bytes");
  if (vertex_count * 12 > range)
    throw DeviceError("body depth: " + std::to_string(vertex_count) +
                      " vertices exceed one storage-buffer binding on this device (" + std::to_string(range) +
                      " bytes); decimate the mesh");
  const gpu::BufferRange depth_map = gpu::sub_range(depth, 4, 0, pixels);
  stream.fill(depth_map, kInfBits);
  if (triangle_count == 0 || vertex_count == 0) return;

  const gpu::Kernel& vertices_kernel = context.kernel("geometry/mesh_depth_vertices", {{0, kWorkgroup}});
  const gpu::Kernel& setup_kernel = context.kernel("geometry/mesh_depth_setup", {{0, kWorkgroup}});
  const gpu::Kernel& raster_kernel = context.kernel("geometry/mesh_depth_raster", {{0, kWorkgroup}});

  const gpu::BufferRange cam = stream.scratch(vertex_count * 12, "body depth: camera-space vertices");
  VertexPush vp{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) vp.rows[4 * r + c] = camera.world_to_camera[c][r];
  vp.vertices = std::uint32_t(vertex_count);
  stream.dispatch(vertices_kernel, {gpu::sub_range(positions, 4, 0, vertex_count * 3), cam}, vp,
                  gpu::Elements(vertex_count));

  // Chunks of triangles: every array fits a binding and the chunk's items fit 32 bits.
  const std::uint64_t max_tiles = tiles_along(camera.width, options.tile) * tiles_along(camera.height, options.tile);
  std::uint64_t chunk = gpu::items_per_chunk(context, {12, 16, 4});
  const std::uint64_t align = std::max<std::uint64_t>(1, context.info().limits.min_storage_buffer_offset_alignment);
  const std::uint64_t by_items = 0xffffffffull / max_tiles;
  if (by_items < chunk) chunk = std::max<std::uint64_t>(align, by_items / align * align);
  const DepthPush base = depth_push(camera, options.tile);
  for (std::uint64_t first = 0; first < triangle_count; first += chunk) {
    const std::uint64_t count = std::min(chunk, triangle_count - first);
    const gpu::BufferRange tris = gpu::sub_range(triangles, 4, first * 3, count * 3);
    const gpu::BufferRange boxes = stream.scratch(count * 16, "body depth: triangle boxes");
    const gpu::BufferRange offsets = stream.scratch(count * 4, "body depth: tile offsets");
    const gpu::BufferRange total = stream.scratch(4, "body depth: tile total");
    DepthPush push = base;
    push.triangles = std::uint32_t(count);
    stream.dispatch(setup_kernel, {tris, cam, boxes, offsets, depth_map}, push, gpu::Elements(count));
    gpu::exclusive_scan(stream, offsets, offsets, total);
    // A fixed grid striding over the items of the big triangles (the setup pass drew the others).
    push.stride = std::uint32_t(std::clamp<std::uint64_t>(count / 8, 4096, 1u << 18) / kWorkgroup * kWorkgroup);
    stream.dispatch(raster_kernel, {tris, cam, boxes, offsets, total, depth_map}, push, gpu::Elements(push.stride));
  }
}

std::vector<float> mesh_depth(gpu::Context& context, const DepthCamera& camera, std::span<const float> positions,
                              std::span<const std::uint32_t> triangles, const MeshDepthOptions& options) {
  validate(camera);
  check_tile(options);
  check_mesh(positions, triangles);
  const std::uint64_t pixels = std::uint64_t(camera.width) * camera.height;
  const std::uint64_t vertices = positions.size() / 3, faces = triangles.size() / 3;
  gpu::Buffer<float> d_depth(context, pixels, "body depth map");
  gpu::Stream stream(context);
  if (faces == 0 || vertices == 0) {
    mesh_depth(stream, camera, {}, 0, {}, 0, d_depth, options);
    stream.submit_and_wait();
    return d_depth.download();
  }
  gpu::Buffer<float> d_positions(context, positions, "body depth: mesh positions");
  gpu::Buffer<std::uint32_t> d_triangles(context, triangles, "body depth: mesh triangles");
  mesh_depth(stream, camera, d_positions, vertices, d_triangles, faces, d_depth, options);
  stream.submit_and_wait();
  return d_depth.download();
}

std::vector<float> mesh_depth_ref(const DepthCamera& camera, std::span<const float> positions,
                                  std::span<const std::uint32_t> triangles) {
  validate(camera);
  check_mesh(positions, triangles);
  std::vector<float> depth(std::size_t(camera.width) * camera.height, kNoDepth);
  const DepthPush pc = depth_push(camera, 1);
  std::vector<V3> cam(positions.size() / 3);
  for (std::size_t i = 0; i < cam.size(); ++i) cam[i] = to_camera(camera, &positions[3 * i]);
  for (std::size_t f = 0; f < triangles.size() / 3; ++f) {
    const V3 v[3] = {cam[triangles[3 * f]], cam[triangles[3 * f + 1]], cam[triangles[3 * f + 2]]};
    raster_ref(pc, v, setup_box(pc, v), depth.data());
  }
  return depth;
}

}  // namespace nf::geometry
