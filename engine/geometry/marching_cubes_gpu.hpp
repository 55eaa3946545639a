#pragma once
// Marching cubes on the GPU: the mesh of marching_cubes() (same generated case table, inside rule
// value < iso, vertices linearly interpolated on the grid edges, same winding, normals from the
// interpolated central-difference gradient), up to the order of vertices and triangles.
// Shaders: shaders/geometry/marching_cubes_{count,emit}.comp, shared GLSL in
// shaders/include/nf_marching_cubes.glsl.
//
// Count then emit, welded: pass 1 flags each grid edge (+x, +y, +z of every point) that crosses the
// iso-value, counts each cell's triangles and records the first NaN/Inf sample; exclusive scans give
// every crossing edge its vertex index and every cell its first triangle. One readback of the totals
// sizes the outputs, then pass 2 writes each crossing edge's vertex and each cell's triangles
// (indices: the scanned ids of the cell's edges).
//
// Large grids: both passes run over slabs of z-layers sized so that every range a kernel binds fits
// one storage-buffer binding (maxStorageBufferRange); the scans chunk by themselves. Limits, each
// refused with a DeviceError that names it: grid edges (3 per point) and triangles (at most
// kMcMaxTriangles per cell) are numbered in 32 bits, so 3 * points and 5 * cells must stay below
// 2^32 (about 950^3 samples); one slab of a single layer must fit a binding (about 24 bytes per
// point of an xy-plane, plus that layer's vertices and triangles at 12 bytes each).
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "engine/gpu/buffer.hpp"
#include "engine/geometry/mesh.hpp"

namespace nf::geometry {

struct MarchingCubesGpuOptions {
  // The largest binding, in bytes, the extractor plans with; 0: the device's maxStorageBufferRange.
  // Tests lower it to run the slab path on small grids.
  std::uint64_t max_binding_bytes = 0;
};

// values: a device range of dims.x * dims.y * dims.z floats, x fastest, with the meaning of
// marching_cubes() (sample (i,j,k) at origin + (i,j,k) * voxel_size); no work still in flight may
// write it. Throws InputError as marching_cubes() does (negative dims, non-positive or non-finite
// voxel size, non-finite origin or iso, a NaN or Inf sample: the first one by index is named). A grid
// thinner than 2 samples gives an empty mesh without touching the device.
geometry::Mesh marching_cubes_gpu(gpu::Context& context, gpu::BufferRange values, glm::ivec3 dims, glm::vec3 origin,
                            glm::vec3 voxel_size, float iso = 0.f, const MarchingCubesGpuOptions& options = {});

// Host convenience: uploads `values` (which must hold exactly dims.x * dims.y * dims.z samples).
geometry::Mesh marching_cubes_gpu(gpu::Context& context, const std::vector<float>& values, glm::ivec3 dims, glm::vec3 origin,
                            glm::vec3 voxel_size, float iso = 0.f, const MarchingCubesGpuOptions& options = {});

}  // namespace nf::geometry
