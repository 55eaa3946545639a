#include "engine/nn/hash_grid.hpp"

#include <random>

#include "engine/core/error.hpp"
#include "engine/gpu/context.hpp"
#include "engine/gpu/kernel.hpp"

namespace nf::nn {
namespace {

struct HashGridPush {
  std::uint32_t batch, levels, features, log2_table, out_stride, dense_mask, has_grad_points, accumulate_points;
  std::uint32_t resolution[16];
  std::uint32_t out_offset;
};
constexpr std::uint32_t kWorkgroup = 64;

HashGridPush make_push(const HashGridConfig& c, std::uint32_t batch, HashGridLayout layout) {
  HashGridPush p{batch, c.levels, c.features, c.log2_table, layout.stride, 0, 0, 0, {}, layout.offset};
  for (std::uint32_t l = 0; l < c.levels; ++l) {
    p.resolution[l] = c.resolution(l);
    if (c.dense(l)) p.dense_mask |= 1u << l;
  }
  return p;
}

}  // namespace

HashGrid::HashGrid(const HashGridConfig& c) : config_(c) {
  if (c.levels < 1 || c.levels > 16) throw InputError("hash grid levels must be 1..16, got " + std::to_string(c.levels));
  if (c.features != 1 && c.features != 2 && c.features != 4)
    throw InputError("hash grid features per level must be 1, 2 or 4, got " + std::to_string(c.features));
  if (c.log2_table < 4 || c.log2_table > 24)
    throw InputError("hash grid log2_table must be 4..24, got " + std::to_string(c.log2_table));
  if (c.base_resolution < 1 || c.max_resolution < c.base_resolution || c.max_resolution > (1u << 20))
    throw InputError("hash grid resolutions must satisfy 1 <= base_resolution <= max_resolution <= 2^20");
}

std::vector<float> HashGrid::initial_table(unsigned seed) const {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1e-4f, 1e-4f);
  std::vector<float> t(config_.parameter_count());
  for (float& x : t) x = u(rng);
  return t;
}

HashGridLayout HashGrid::resolve(HashGridLayout layout) const {
  if (layout.stride == 0) layout.stride = config_.output_stride();
  if (layout.offset + config_.output_dim() > layout.stride)
    throw InputError("hash grid: " + std::to_string(config_.output_dim()) + " features from column " +
                     std::to_string(layout.offset) + " do not fit rows of " + std::to_string(layout.stride));
  return layout;
}

void HashGrid::forward(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange table, gpu::BufferRange encoded,
                       std::uint32_t batch, HashGridLayout layout) const {
  layout = resolve(layout);
  gpu::require_bytes(points, std::uint64_t(batch) * 12, "hash grid points");
  gpu::require_bytes(table, config_.parameter_count() * 4, "hash grid table");
  gpu::require_bytes(encoded, std::uint64_t(batch) * layout.stride * 4, "hash grid output");
  const gpu::Kernel& k = stream.context().kernel("nn/hash_grid_fwd", {{0, kWorkgroup}});
  stream.dispatch(k, {points, table, encoded}, make_push(config_, batch, layout), gpu::Elements(batch));
}

void HashGrid::backward(gpu::Stream& stream, gpu::BufferRange points, gpu::BufferRange table,
                        gpu::BufferRange grad_encoded, gpu::BufferRange grad_table, gpu::BufferRange grad_points,
                        std::uint32_t batch, bool accumulate_points, HashGridLayout layout) const {
  layout = resolve(layout);
  gpu::require_bytes(points, std::uint64_t(batch) * 12, "hash grid points");
  gpu::require_bytes(table, config_.parameter_count() * 4, "hash grid table");
  gpu::require_bytes(grad_table, config_.parameter_count() * 4, "hash grid table gradient");
  gpu::require_bytes(grad_encoded, std::uint64_t(batch) * layout.stride * 4, "hash grid output gradient");
  if (grad_points.size) gpu::require_bytes(grad_points, std::uint64_t(batch) * 12, "hash grid point gradient");
  const gpu::Kernel& k = stream.context().kernel("nn/hash_grid_bwd", {{0, kWorkgroup}});
  HashGridPush push = make_push(config_, batch, layout);
  push.has_grad_points = grad_points.size ? 1u : 0u;
  push.accumulate_points = accumulate_points ? 1u : 0u;
  stream.dispatch(k, {points, table, grad_encoded, grad_table, grad_points}, push, gpu::Elements(batch));
}

}  // namespace nf::nn
